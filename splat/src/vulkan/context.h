// The Vulkan instance, the chosen device and its compute queue. Owned by a rasterizer and
// passed to what needs it; no globals.
#pragma once
#include <vulkan/vulkan.h>

#include <atomic>
#include <cstdint>
#include <string>
#include <vector>

#include "splat/vulkan_rasterizer.h"

namespace splat::vk {

// Throws splat::Error("vulkan: <what> failed: VK_ERROR_...") unless result is VK_SUCCESS.
void vk_check(VkResult result, const char* what);

class Context {
 public:
  // options.device: an index of list_vulkan_devices(), or -1 for the best usable device
  // (discrete, then integrated, then virtual, then CPU). Enables float atomics if asked for
  // and offered. Throws splat::Error if no device is usable.
  explicit Context(const VulkanOptions& options);
  ~Context();
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;

  VkDevice device() const { return device_; }
  VkQueue queue() const { return queue_; }
  VkCommandPool command_pool() const { return command_pool_; }
  const VulkanDeviceInfo& info() const { return info_; }
  bool float_atomics_enabled() const { return float_atomics_; }
  bool map_device_memory() const { return map_device_memory_; }
  // Nanoseconds per timestamp tick on the compute queue; 0 if it has no timestamps.
  double timestamp_period_ns() const { return timestamp_period_ns_; }
  // Index of a memory type allowed by type_bits that has all of `required`, preferring
  // ones that also have `preferred`. Throws if none.
  uint32_t memory_type(uint32_t type_bits, VkMemoryPropertyFlags required,
                       VkMemoryPropertyFlags preferred) const;
  VkMemoryPropertyFlags memory_flags(uint32_t type_index) const;
  // Device memory allocated through Buffer, in bytes.
  std::size_t allocated_bytes() const { return allocated_.load(); }
  void count_allocation(std::size_t bytes, bool freed) {
    if (freed)
      allocated_ -= bytes;
    else
      allocated_ += bytes;
  }

 private:
  VkInstance instance_ = VK_NULL_HANDLE;
  VkPhysicalDevice physical_ = VK_NULL_HANDLE;
  VkDevice device_ = VK_NULL_HANDLE;
  VkQueue queue_ = VK_NULL_HANDLE;
  VkCommandPool command_pool_ = VK_NULL_HANDLE;
  VkPhysicalDeviceMemoryProperties memory_{};
  VulkanDeviceInfo info_;
  std::atomic<std::size_t> allocated_{0};
  bool float_atomics_ = false;
  bool map_device_memory_ = true;
  double timestamp_period_ns_ = 0;
};

// Creates an instance for Vulkan 1.2; throws if the loader or driver is missing.
VkInstance create_instance();
// What a device offers and whether the backend can run on it (see VulkanDeviceInfo::problem).
VulkanDeviceInfo describe_device(VkPhysicalDevice physical, int index);

}  // namespace splat::vk
