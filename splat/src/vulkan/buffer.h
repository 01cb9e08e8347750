// A device storage buffer that grows on demand. Device-local memory; mapped persistently when
// that memory is also host-visible, coherent and cached (lavapipe, integrated GPUs) and the
// context allows it, otherwise filled and read through staging copies (see CommandBatch).
// A discrete GPU's host-visible VRAM (resizable BAR) is not mapped: host reads of it are
// uncached, about 1000x slower than a staging copy.
#pragma once
#include <cstddef>

#include "vulkan/context.h"

namespace splat::vk {

class Buffer {
 public:
  Buffer() = default;
  explicit Buffer(Context& context) : context_(&context) {}
  ~Buffer() { release(); }
  Buffer(const Buffer&) = delete;
  Buffer& operator=(const Buffer&) = delete;
  Buffer(Buffer&& other) noexcept { *this = std::move(other); }
  Buffer& operator=(Buffer&& other) noexcept;

  // Makes room for `bytes` (at least 256). Growing discards the contents; capacity grows by
  // half again so a slowly growing map does not reallocate every frame.
  void reserve(std::size_t bytes);
  // Host-visible, coherent memory for staging copies (prefers cached memory for reads);
  // always mapped.
  void reserve_staging(std::size_t bytes);

  VkBuffer handle() const { return buffer_; }
  std::size_t capacity() const { return capacity_; }
  void* mapped() const { return mapped_; }  // null unless host-visible

 private:
  // Maps the memory when its type has every flag in `map_when`.
  void allocate(std::size_t bytes, VkMemoryPropertyFlags required, VkMemoryPropertyFlags preferred,
                VkMemoryPropertyFlags map_when);
  void release();

  Context* context_ = nullptr;
  VkBuffer buffer_ = VK_NULL_HANDLE;
  VkDeviceMemory memory_ = VK_NULL_HANDLE;
  std::size_t capacity_ = 0;
  void* mapped_ = nullptr;
};

}  // namespace splat::vk
