#include "commands/backend.h"

#include "splat/error.h"
#include "splat/vulkan_rasterizer.h"

namespace app {
namespace {

std::unique_ptr<splat::Rasterizer> make_cpu(const BackendChoice& choice) {
  return splat::make_cpu_rasterizer({choice.threads});
}

// The Vulkan device `auto` would take, or why there is none worth taking. A CPU Vulkan driver
// (lavapipe) is skipped: the CPU backend runs the same maths natively, faster.
std::string auto_vulkan_device(const BackendChoice& choice, int& device) {
  if (!splat::vulkan_backend_built()) return "this build has no Vulkan backend";
  std::vector<splat::VulkanDeviceInfo> devices;
  try {
    devices = splat::list_vulkan_devices();
  } catch (const splat::Error& e) {
    return e.what();
  }
  std::string why = devices.empty() ? "no Vulkan device" : "";
  for (const auto& d : devices) {
    if (choice.device >= 0 && d.index != choice.device) continue;
    if (!d.usable) {
      why += (why.empty() ? "" : "; ") + d.name + ": " + d.problem;
    } else if (d.type == "cpu" && choice.device < 0) {
      why += (why.empty() ? "" : "; ") + d.name + " is a CPU driver";
    } else if (device < 0 || d.type == "discrete") {
      device = d.index;
    }
  }
  return why;
}

}  // namespace

std::unique_ptr<splat::Rasterizer> make_rasterizer(const BackendChoice& choice, std::string& note) {
  if (choice.backend == "cpu") {
    auto rasterizer = make_cpu(choice);
    note = "backend: " + rasterizer->name();
    return rasterizer;
  }
  if (choice.backend == "vulkan") {
    auto rasterizer = splat::make_vulkan_rasterizer({choice.device});
    note = "backend: " + rasterizer->name();
    return rasterizer;
  }
  if (choice.backend == "auto") {
    int device = -1;
    const std::string why = auto_vulkan_device(choice, device);
    if (device >= 0) {
      auto rasterizer = splat::make_vulkan_rasterizer({device});
      note = "backend auto: using " + rasterizer->name() + " (a Vulkan GPU is present)";
      return rasterizer;
    }
    auto rasterizer = make_cpu(choice);
    note = "backend auto: using " + rasterizer->name() + " (no Vulkan GPU: " + why + ")";
    return rasterizer;
  }
  throw splat::Error("backend '" + choice.backend + "': expected auto, cpu or vulkan");
}

}  // namespace app
