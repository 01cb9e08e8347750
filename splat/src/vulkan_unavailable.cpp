// The Vulkan entry points of a build without the Vulkan backend (GSLAM_ENABLE_VULKAN off, or
// libvulkan-dev / glslang-tools missing at configure time).
#include "splat/error.h"
#include "splat/vulkan_rasterizer.h"

namespace splat {

bool vulkan_backend_built() { return false; }

std::vector<VulkanDeviceInfo> list_vulkan_devices() {
  throw Error(
      "vulkan: this build has no Vulkan backend (configure with libvulkan-dev and glslang-tools)");
}

std::unique_ptr<Rasterizer> make_vulkan_rasterizer(const VulkanOptions&) {
  list_vulkan_devices();
  return nullptr;
}

}  // namespace splat
