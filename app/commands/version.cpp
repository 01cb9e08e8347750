#include "commands/version.h"

#include "splat/vulkan_rasterizer.h"
#include "viewer/viewer_window.h"

namespace app {

std::string version_text() {
  return std::string("gslam ") + gslam_version() + " (commit " + gslam_git_commit() + ")\n" +
         "backends: cpu" + (splat::vulkan_backend_built() ? ", vulkan" : " (built without Vulkan)") + "\n" +
         "viewer: " + (viewer_built() ? "yes (GLFW)" : "no (built without GLFW)");
}

}  // namespace app
