#include "vulkan/context.h"

#include <algorithm>
#include <string>

#include "shader_io.h"
#include "splat/error.h"

namespace splat::vk {
namespace {

const char* result_name(VkResult r) {
  switch (r) {
    case VK_NOT_READY:
      return "VK_NOT_READY";
    case VK_TIMEOUT:
      return "VK_TIMEOUT";
    case VK_INCOMPLETE:
      return "VK_INCOMPLETE";
    case VK_ERROR_OUT_OF_HOST_MEMORY:
      return "VK_ERROR_OUT_OF_HOST_MEMORY";
    case VK_ERROR_OUT_OF_DEVICE_MEMORY:
      return "VK_ERROR_OUT_OF_DEVICE_MEMORY";
    case VK_ERROR_INITIALIZATION_FAILED:
      return "VK_ERROR_INITIALIZATION_FAILED";
    case VK_ERROR_DEVICE_LOST:
      return "VK_ERROR_DEVICE_LOST";
    case VK_ERROR_MEMORY_MAP_FAILED:
      return "VK_ERROR_MEMORY_MAP_FAILED";
    case VK_ERROR_LAYER_NOT_PRESENT:
      return "VK_ERROR_LAYER_NOT_PRESENT";
    case VK_ERROR_EXTENSION_NOT_PRESENT:
      return "VK_ERROR_EXTENSION_NOT_PRESENT";
    case VK_ERROR_FEATURE_NOT_PRESENT:
      return "VK_ERROR_FEATURE_NOT_PRESENT";
    case VK_ERROR_INCOMPATIBLE_DRIVER:
      return "VK_ERROR_INCOMPATIBLE_DRIVER";
    case VK_ERROR_TOO_MANY_OBJECTS:
      return "VK_ERROR_TOO_MANY_OBJECTS";
    case VK_ERROR_OUT_OF_POOL_MEMORY:
      return "VK_ERROR_OUT_OF_POOL_MEMORY";
    default:
      return "VkResult error";
  }
}

std::string version_string(uint32_t v) {
  return std::to_string(VK_API_VERSION_MAJOR(v)) + "." + std::to_string(VK_API_VERSION_MINOR(v)) +
         "." + std::to_string(VK_API_VERSION_PATCH(v));
}

// Preference of device types for `--device` left at -1: lower is better.
int type_rank(const std::string& type) {
  if (type == "discrete") return 0;
  if (type == "integrated") return 1;
  if (type == "virtual") return 2;
  if (type == "cpu") return 3;
  return 4;
}

// Storage buffers the widest stage binds (project_backward.comp).
constexpr uint32_t kMostStorageBuffers = 16;
// Shared memory the largest stage needs (rasterize_backward.comp's partial sums and batch).
constexpr uint32_t kSharedBytesNeeded =
    (io::kBackwardBatch * io::kGradSlots * io::kMaxSubgroups + io::kBackwardBatch * 16) * 4;

}  // namespace

void vk_check(VkResult result, const char* what) {
  if (result != VK_SUCCESS) {
    throw Error(std::string("vulkan: ") + what + " failed: " + result_name(result));
  }
}

VkInstance create_instance() {
  VkApplicationInfo app{VK_STRUCTURE_TYPE_APPLICATION_INFO};
  app.pApplicationName = "gslam";
  app.apiVersion = VK_API_VERSION_1_2;
  VkInstanceCreateInfo info{VK_STRUCTURE_TYPE_INSTANCE_CREATE_INFO};
  info.pApplicationInfo = &app;
  VkInstance instance = VK_NULL_HANDLE;
  const VkResult r = vkCreateInstance(&info, nullptr, &instance);
  if (r != VK_SUCCESS) {
    throw Error(std::string("vulkan: no usable Vulkan loader or driver (vkCreateInstance: ") +
                result_name(r) + "); install mesa-vulkan-drivers or a GPU driver");
  }
  return instance;
}

VulkanDeviceInfo describe_device(VkPhysicalDevice physical, int index) {
  VkPhysicalDeviceSubgroupProperties subgroup{
      VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SUBGROUP_PROPERTIES};
  VkPhysicalDeviceProperties2 props{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_PROPERTIES_2};
  props.pNext = &subgroup;
  vkGetPhysicalDeviceProperties2(physical, &props);
  const VkPhysicalDeviceProperties& p = props.properties;
  VulkanDeviceInfo info;
  info.index = index;
  info.name = p.deviceName;
  switch (p.deviceType) {
    case VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU:
      info.type = "discrete";
      break;
    case VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU:
      info.type = "integrated";
      break;
    case VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU:
      info.type = "virtual";
      break;
    case VK_PHYSICAL_DEVICE_TYPE_CPU:
      info.type = "cpu";
      break;
    default:
      info.type = "other";
      break;
  }
  info.api_version = version_string(p.apiVersion);
  info.subgroup_size = subgroup.subgroupSize;
  const VkSubgroupFeatureFlags ops = VK_SUBGROUP_FEATURE_BASIC_BIT | VK_SUBGROUP_FEATURE_VOTE_BIT |
                                     VK_SUBGROUP_FEATURE_ARITHMETIC_BIT;
  VkPhysicalDeviceFeatures features;
  vkGetPhysicalDeviceFeatures(physical, &features);
  if (p.apiVersion < VK_API_VERSION_1_2) {
    info.problem = "Vulkan " + info.api_version + " < 1.2";
  } else if (!features.shaderFloat64) {
    info.problem = "no shaderFloat64 (camera transform in double)";
  } else if (!(subgroup.supportedStages & VK_SHADER_STAGE_COMPUTE_BIT) ||
             (subgroup.supportedOperations & ops) != ops) {
    info.problem = "no subgroup vote and arithmetic in compute shaders";
  } else if (subgroup.subgroupSize < io::kGroupSize / io::kMaxSubgroups) {
    info.problem = "subgroup size " + std::to_string(subgroup.subgroupSize) + " < 8";
  } else if (p.limits.maxPerStageDescriptorStorageBuffers < kMostStorageBuffers) {
    info.problem = "only " + std::to_string(p.limits.maxPerStageDescriptorStorageBuffers) +
                   " storage buffers per stage (needs " + std::to_string(kMostStorageBuffers) + ")";
  } else if (p.limits.maxComputeSharedMemorySize < kSharedBytesNeeded) {
    info.problem = "only " + std::to_string(p.limits.maxComputeSharedMemorySize) +
                   " bytes of shared memory (needs " + std::to_string(kSharedBytesNeeded) + ")";
  } else {
    uint32_t families = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(physical, &families, nullptr);
    std::vector<VkQueueFamilyProperties> props_list(families);
    vkGetPhysicalDeviceQueueFamilyProperties(physical, &families, props_list.data());
    const bool compute = std::any_of(props_list.begin(), props_list.end(), [](const auto& q) {
      return (q.queueFlags & VK_QUEUE_COMPUTE_BIT) != 0;
    });
    if (!compute) info.problem = "no compute queue";
  }
  info.usable = info.problem.empty();
  uint32_t extension_count = 0;
  vkEnumerateDeviceExtensionProperties(physical, nullptr, &extension_count, nullptr);
  std::vector<VkExtensionProperties> extensions(extension_count);
  vkEnumerateDeviceExtensionProperties(physical, nullptr, &extension_count, extensions.data());
  const bool has_atomic_float =
      std::any_of(extensions.begin(), extensions.end(), [](const auto& e) {
        return std::string(e.extensionName) == VK_EXT_SHADER_ATOMIC_FLOAT_EXTENSION_NAME;
      });
  if (has_atomic_float) {
    VkPhysicalDeviceShaderAtomicFloatFeaturesEXT atomic{
        VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SHADER_ATOMIC_FLOAT_FEATURES_EXT};
    VkPhysicalDeviceFeatures2 features2{VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_FEATURES_2};
    features2.pNext = &atomic;
    vkGetPhysicalDeviceFeatures2(physical, &features2);
    info.float_atomics = atomic.shaderBufferFloat32AtomicAdd == VK_TRUE;
  }
  return info;
}

Context::Context(const VulkanOptions& options) : map_device_memory_(options.map_device_memory) {
  const int device_index = options.device;
  instance_ = create_instance();
  try {
    uint32_t count = 0;
    vk_check(vkEnumeratePhysicalDevices(instance_, &count, nullptr), "vkEnumeratePhysicalDevices");
    std::vector<VkPhysicalDevice> physicals(count);
    vk_check(vkEnumeratePhysicalDevices(instance_, &count, physicals.data()),
             "vkEnumeratePhysicalDevices");
    if (count == 0) throw Error("vulkan: no Vulkan device found");
    int chosen = -1;
    if (device_index >= 0) {
      if (device_index >= static_cast<int>(count)) {
        throw Error("vulkan: --device " + std::to_string(device_index) + " out of range; " +
                    std::to_string(count) + " device(s) found");
      }
      info_ = describe_device(physicals[device_index], device_index);
      if (!info_.usable) {
        throw Error("vulkan: device " + std::to_string(device_index) + " (" + info_.name +
                    ") cannot run the backend: " + info_.problem);
      }
      chosen = device_index;
    } else {
      std::string problems;
      for (uint32_t i = 0; i < count; ++i) {
        VulkanDeviceInfo candidate = describe_device(physicals[i], static_cast<int>(i));
        if (!candidate.usable) {
          problems += (problems.empty() ? "" : "; ") + candidate.name + ": " + candidate.problem;
          continue;
        }
        if (chosen < 0 || type_rank(candidate.type) < type_rank(info_.type)) {
          chosen = static_cast<int>(i);
          info_ = candidate;
        }
      }
      if (chosen < 0) throw Error("vulkan: no usable device (" + problems + ")");
    }
    physical_ = physicals[chosen];
    vkGetPhysicalDeviceMemoryProperties(physical_, &memory_);

    uint32_t families = 0;
    vkGetPhysicalDeviceQueueFamilyProperties(physical_, &families, nullptr);
    std::vector<VkQueueFamilyProperties> queue_props(families);
    vkGetPhysicalDeviceQueueFamilyProperties(physical_, &families, queue_props.data());
    uint32_t family = 0;
    for (uint32_t f = 0; f < families; ++f) {
      if (queue_props[f].queueFlags & VK_QUEUE_COMPUTE_BIT) {
        family = f;
        break;
      }
    }
    if (queue_props[family].timestampValidBits > 0) {
      VkPhysicalDeviceProperties props;
      vkGetPhysicalDeviceProperties(physical_, &props);
      timestamp_period_ns_ = props.limits.timestampPeriod;
    }
    const float priority = 1.0f;
    VkDeviceQueueCreateInfo queue_info{VK_STRUCTURE_TYPE_DEVICE_QUEUE_CREATE_INFO};
    queue_info.queueFamilyIndex = family;
    queue_info.queueCount = 1;
    queue_info.pQueuePriorities = &priority;
    VkPhysicalDeviceFeatures features{};
    features.shaderFloat64 = VK_TRUE;
    VkDeviceCreateInfo device_info{VK_STRUCTURE_TYPE_DEVICE_CREATE_INFO};
    device_info.pEnabledFeatures = &features;
    float_atomics_ = options.float_atomics && info_.float_atomics;
    VkPhysicalDeviceShaderAtomicFloatFeaturesEXT atomic{
        VK_STRUCTURE_TYPE_PHYSICAL_DEVICE_SHADER_ATOMIC_FLOAT_FEATURES_EXT};
    const char* atomic_extension = VK_EXT_SHADER_ATOMIC_FLOAT_EXTENSION_NAME;
    if (float_atomics_) {
      atomic.shaderBufferFloat32AtomicAdd = VK_TRUE;
      device_info.pNext = &atomic;
      device_info.enabledExtensionCount = 1;
      device_info.ppEnabledExtensionNames = &atomic_extension;
    }
    device_info.queueCreateInfoCount = 1;
    device_info.pQueueCreateInfos = &queue_info;
    vk_check(vkCreateDevice(physical_, &device_info, nullptr, &device_), "vkCreateDevice");
    vkGetDeviceQueue(device_, family, 0, &queue_);
    VkCommandPoolCreateInfo pool_info{VK_STRUCTURE_TYPE_COMMAND_POOL_CREATE_INFO};
    pool_info.flags = VK_COMMAND_POOL_CREATE_RESET_COMMAND_BUFFER_BIT;
    pool_info.queueFamilyIndex = family;
    vk_check(vkCreateCommandPool(device_, &pool_info, nullptr, &command_pool_),
             "vkCreateCommandPool");
  } catch (...) {
    if (device_) vkDestroyDevice(device_, nullptr);
    vkDestroyInstance(instance_, nullptr);
    throw;
  }
}

Context::~Context() {
  vkDeviceWaitIdle(device_);
  vkDestroyCommandPool(device_, command_pool_, nullptr);
  vkDestroyDevice(device_, nullptr);
  vkDestroyInstance(instance_, nullptr);
}

uint32_t Context::memory_type(uint32_t type_bits, VkMemoryPropertyFlags required,
                              VkMemoryPropertyFlags preferred) const {
  int fallback = -1;
  for (uint32_t i = 0; i < memory_.memoryTypeCount; ++i) {
    if (!(type_bits & (1u << i))) continue;
    const VkMemoryPropertyFlags flags = memory_.memoryTypes[i].propertyFlags;
    if ((flags & required) != required) continue;
    if ((flags & preferred) == preferred) return i;
    if (fallback < 0) fallback = static_cast<int>(i);
  }
  if (fallback < 0) throw Error("vulkan: no memory type with the required properties");
  return static_cast<uint32_t>(fallback);
}

VkMemoryPropertyFlags Context::memory_flags(uint32_t type_index) const {
  return memory_.memoryTypes[type_index].propertyFlags;
}

}  // namespace splat::vk
