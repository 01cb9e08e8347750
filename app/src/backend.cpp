#include "app/backend.h"

#include "splat/error.h"

namespace app {

std::unique_ptr<splat::Rasterizer> make_rasterizer(const BackendChoice& choice, std::string& note) {
  if (choice.backend == "cpu" || choice.backend == "auto") {
    auto rasterizer = splat::make_cpu_rasterizer({choice.threads});
    note = choice.backend == "auto" ? "backend auto: using " + rasterizer->name() +
                                          " (this build has no Vulkan backend)"
                                    : "backend: " + rasterizer->name();
    return rasterizer;
  }
  if (choice.backend == "vulkan") {
    throw splat::Error("backend vulkan: this build has no Vulkan backend; use --backend cpu");
  }
  throw splat::Error("backend '" + choice.backend + "': expected auto, cpu or vulkan");
}

}  // namespace app
