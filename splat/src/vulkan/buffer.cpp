#include "vulkan/buffer.h"

#include <algorithm>
#include <utility>

namespace splat::vk {

Buffer& Buffer::operator=(Buffer&& other) noexcept {
  if (this != &other) {
    release();
    context_ = other.context_;
    buffer_ = std::exchange(other.buffer_, VK_NULL_HANDLE);
    memory_ = std::exchange(other.memory_, VK_NULL_HANDLE);
    capacity_ = std::exchange(other.capacity_, 0);
    mapped_ = std::exchange(other.mapped_, nullptr);
  }
  return *this;
}

void Buffer::reserve(std::size_t bytes) {
  if (bytes <= capacity_) return;
  const std::size_t grown = std::max<std::size_t>({bytes, capacity_ + capacity_ / 2, 256});
  constexpr VkMemoryPropertyFlags kHostFriendly = VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT |
                                                  VK_MEMORY_PROPERTY_HOST_COHERENT_BIT |
                                                  VK_MEMORY_PROPERTY_HOST_CACHED_BIT;
  if (context_->map_device_memory()) {
    allocate(grown, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, kHostFriendly, kHostFriendly);
  } else {
    // The unmappable sentinel: no memory type has every bit set.
    allocate(grown, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT, 0, ~VkMemoryPropertyFlags(0));
  }
}

void Buffer::reserve_staging(std::size_t bytes) {
  if (bytes <= capacity_) return;
  const std::size_t grown = std::max<std::size_t>({bytes, capacity_ + capacity_ / 2, 256});
  constexpr VkMemoryPropertyFlags kHost =
      VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT;
  allocate(grown, kHost, VK_MEMORY_PROPERTY_HOST_CACHED_BIT, kHost);
}

void Buffer::allocate(std::size_t bytes, VkMemoryPropertyFlags required,
                      VkMemoryPropertyFlags preferred, VkMemoryPropertyFlags map_when) {
  release();
  VkDevice device = context_->device();
  VkBufferCreateInfo info{VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO};
  info.size = bytes;
  info.usage = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT | VK_BUFFER_USAGE_TRANSFER_SRC_BIT |
               VK_BUFFER_USAGE_TRANSFER_DST_BIT;
  info.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  vk_check(vkCreateBuffer(device, &info, nullptr, &buffer_), "vkCreateBuffer");
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(device, buffer_, &req);
  const uint32_t type = context_->memory_type(req.memoryTypeBits, required, preferred);
  VkMemoryAllocateInfo alloc{VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO};
  alloc.allocationSize = req.size;
  alloc.memoryTypeIndex = type;
  const VkResult r = vkAllocateMemory(device, &alloc, nullptr, &memory_);
  if (r != VK_SUCCESS) {
    vkDestroyBuffer(device, buffer_, nullptr);
    buffer_ = VK_NULL_HANDLE;
    vk_check(r, ("vkAllocateMemory of " + std::to_string(bytes) + " bytes").c_str());
  }
  vk_check(vkBindBufferMemory(device, buffer_, memory_, 0), "vkBindBufferMemory");
  capacity_ = bytes;
  context_->count_allocation(capacity_, false);
  if ((context_->memory_flags(type) & map_when) == map_when) {
    vk_check(vkMapMemory(device, memory_, 0, VK_WHOLE_SIZE, 0, &mapped_), "vkMapMemory");
  }
}

void Buffer::release() {
  if (!context_ || buffer_ == VK_NULL_HANDLE) return;
  VkDevice device = context_->device();
  if (mapped_) vkUnmapMemory(device, memory_);
  vkDestroyBuffer(device, buffer_, nullptr);
  vkFreeMemory(device, memory_, nullptr);
  context_->count_allocation(capacity_, true);
  buffer_ = VK_NULL_HANDLE;
  memory_ = VK_NULL_HANDLE;
  mapped_ = nullptr;
  capacity_ = 0;
}

}  // namespace splat::vk
