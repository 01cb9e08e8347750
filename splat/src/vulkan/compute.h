// Compute pipelines and the command batches that run them. Every stage binds only storage
// buffers (bindings 0..n-1, in the order its .comp declares them) and up to 16 bytes of push
// constants; a batch records dispatches with a full barrier between them, then runs them.
#pragma once
#include <atomic>
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "vulkan/buffer.h"

namespace splat::vk {

class Kernel {
 public:
  Kernel(Context& context, std::span<const uint32_t> spirv, uint32_t bindings, const char* name);
  ~Kernel();
  Kernel(const Kernel&) = delete;
  Kernel& operator=(const Kernel&) = delete;

  VkPipeline pipeline() const { return pipeline_; }
  VkPipelineLayout layout() const { return layout_; }
  VkDescriptorSetLayout set_layout() const { return set_layout_; }
  uint32_t bindings() const { return bindings_; }
  const char* name() const { return name_; }

  static constexpr uint32_t kPushBytes = 16;

 private:
  Context& context_;
  VkDescriptorSetLayout set_layout_ = VK_NULL_HANDLE;
  VkPipelineLayout layout_ = VK_NULL_HANDLE;
  VkPipeline pipeline_ = VK_NULL_HANDLE;
  uint32_t bindings_;
  const char* name_;
};

// Records work into one command buffer; run() submits it, waits, then performs the host side
// of the recorded downloads. Reusable after run().
class CommandBatch {
 public:
  explicit CommandBatch(Context& context);
  ~CommandBatch();
  CommandBatch(const CommandBatch&) = delete;
  CommandBatch& operator=(const CommandBatch&) = delete;

  // Binds `buffers` to bindings 0.. of the kernel (their count must match) and dispatches
  // groups_x x groups_y workgroups; nothing is recorded for zero groups.
  void dispatch(const Kernel& kernel, std::initializer_list<const Buffer*> buffers,
                std::initializer_list<uint32_t> push, uint32_t groups_x, uint32_t groups_y = 1);
  void fill_zero(Buffer& buffer, std::size_t bytes, std::size_t offset = 0);  // offset: 4-byte aligned
  void copy(const Buffer& from, Buffer& to, std::size_t bytes, std::size_t from_offset = 0,
            std::size_t to_offset = 0);
  // Host data to the buffer at `offset` bytes, now when it is mapped (the GPU is idle between
  // batches), else through a staging copy recorded here.
  void upload(Buffer& buffer, const void* data, std::size_t bytes, std::size_t offset = 0);
  // Buffer from `offset` bytes to host memory after run(); `data` must stay valid until then.
  void download(const Buffer& buffer, void* data, std::size_t bytes, std::size_t offset = 0);
  void run();
  // Drops what was recorded since the last run() (nothing is submitted, no download happens):
  // for an operation that failed half-way, so the next run() does not submit its commands.
  void discard();
  // Bytes given to upload() and download() since the last reset (mapped or staged alike);
  // another thread may read them (a run's summary while mapping runs).
  std::size_t uploaded_bytes() const { return uploaded_bytes_.load(std::memory_order_relaxed); }
  std::size_t downloaded_bytes() const { return downloaded_bytes_.load(std::memory_order_relaxed); }
  void reset_transfer_counts() { uploaded_bytes_ = 0, downloaded_bytes_ = 0; }
  // GPU time per kernel name over the batches run so far (timestamps after each dispatch;
  // empty if the queue has none), and a reset.
  const std::map<std::string, double>& kernel_ms() const { return kernel_ms_; }
  void reset_kernel_ms() { kernel_ms_.clear(); }

 private:
  void begin_recording();
  void barrier();
  VkDescriptorSet allocate_set(const Kernel& kernel);

  Context& context_;
  VkCommandBuffer commands_ = VK_NULL_HANDLE;
  VkFence fence_ = VK_NULL_HANDLE;
  std::vector<VkDescriptorPool> pools_;
  std::size_t pool_in_use_ = 0;
  bool recording_ = false;
  std::vector<std::function<void()>> after_run_;
  // Staging buffers, reused by the next batch: the n-th transfer of a batch takes the n-th,
  // so a frame-to-frame loop allocates nothing once they have grown.
  Buffer& next_staging(std::size_t bytes);
  std::vector<std::unique_ptr<Buffer>> staging_;
  std::size_t staging_used_ = 0;
  // Timestamps: one at the start of the batch, then one after each dispatch.
  VkQueryPool queries_ = VK_NULL_HANDLE;
  std::vector<const char*> timed_;  // kernel name of each timestamp after the first
  std::map<std::string, double> kernel_ms_;
  std::atomic<std::size_t> uploaded_bytes_{0}, downloaded_bytes_{0};
};

}  // namespace splat::vk
