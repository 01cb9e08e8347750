// The Vulkan compute backend of the rasterizer (shaders/*.comp, SPIR-V embedded at build time).
#pragma once
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "splat/rasterizer.h"

namespace splat {

struct VulkanOptions {
  int device = -1;  // index into list_vulkan_devices(); -1 picks the best usable device
  // Backward reduction: float atomics (VK_EXT_shader_atomic_float) where the device has them,
  // the fastest, or false for the portable one, which is also bit-for-bit deterministic.
  bool float_atomics = true;
  // Let the host read and write device buffers in place where that memory is host-visible,
  // coherent and cached (lavapipe, integrated GPUs). Elsewhere, and always when false, data
  // moves through staging copies: host reads of a discrete GPU's mapped memory (resizable
  // BAR) are uncached and cost more than rendering.
  bool map_device_memory = true;
};

struct VulkanDeviceInfo {
  int index = 0;
  std::string name;
  std::string type;         // "discrete", "integrated", "virtual", "cpu" or "other"
  std::string api_version;  // e.g. "1.3.238"
  uint32_t subgroup_size = 0;
  bool float_atomics = false;  // VK_EXT_shader_atomic_float with shaderBufferFloat32AtomicAdd
  bool usable = false;
  std::string problem;  // why the backend cannot run on it, when not usable
};

// Whether this build contains the Vulkan backend (GSLAM_ENABLE_VULKAN with the packages found).
bool vulkan_backend_built();
// Every physical device the loader reports. Throws splat::Error if the build has no Vulkan
// backend or no Vulkan loader/driver can be initialized.
std::vector<VulkanDeviceInfo> list_vulkan_devices();
// Throws splat::Error naming the reason if no usable device exists or `device` is out of range
// or unusable.
std::unique_ptr<Rasterizer> make_vulkan_rasterizer(const VulkanOptions& options = {});

}  // namespace splat
