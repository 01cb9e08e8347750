#include "vulkan/compute.h"

#include <cstring>
#include <string>

#include "splat/error.h"

namespace splat::vk {
namespace {
constexpr uint32_t kMaxTimestamps = 512;  // per batch; later dispatches go untimed
}  // namespace

Kernel::Kernel(Context& context, std::span<const uint32_t> spirv, uint32_t bindings,
               const char* name)
    : context_(context), bindings_(bindings), name_(name) {
  VkDevice device = context_.device();
  std::vector<VkDescriptorSetLayoutBinding> layout_bindings(bindings);
  for (uint32_t b = 0; b < bindings; ++b) {
    layout_bindings[b] = {b, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT,
                          nullptr};
  }
  VkDescriptorSetLayoutCreateInfo set_info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO};
  set_info.bindingCount = bindings;
  set_info.pBindings = layout_bindings.data();
  vk_check(vkCreateDescriptorSetLayout(device, &set_info, nullptr, &set_layout_),
           "vkCreateDescriptorSetLayout");
  VkPushConstantRange push{VK_SHADER_STAGE_COMPUTE_BIT, 0, kPushBytes};
  VkPipelineLayoutCreateInfo layout_info{VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO};
  layout_info.setLayoutCount = 1;
  layout_info.pSetLayouts = &set_layout_;
  layout_info.pushConstantRangeCount = 1;
  layout_info.pPushConstantRanges = &push;
  vk_check(vkCreatePipelineLayout(device, &layout_info, nullptr, &layout_),
           "vkCreatePipelineLayout");

  VkShaderModuleCreateInfo module_info{VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO};
  module_info.codeSize = spirv.size_bytes();
  module_info.pCode = spirv.data();
  VkShaderModule module = VK_NULL_HANDLE;
  vk_check(vkCreateShaderModule(device, &module_info, nullptr, &module), "vkCreateShaderModule");
  VkComputePipelineCreateInfo pipeline_info{VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO};
  pipeline_info.stage = {VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO,
                         nullptr,
                         0,
                         VK_SHADER_STAGE_COMPUTE_BIT,
                         module,
                         "main",
                         nullptr};
  pipeline_info.layout = layout_;
  const VkResult r =
      vkCreateComputePipelines(device, VK_NULL_HANDLE, 1, &pipeline_info, nullptr, &pipeline_);
  vkDestroyShaderModule(device, module, nullptr);
  vk_check(r, (std::string("vkCreateComputePipelines (") + name + ")").c_str());
}

Kernel::~Kernel() {
  VkDevice device = context_.device();
  vkDestroyPipeline(device, pipeline_, nullptr);
  vkDestroyPipelineLayout(device, layout_, nullptr);
  vkDestroyDescriptorSetLayout(device, set_layout_, nullptr);
}

CommandBatch::CommandBatch(Context& context) : context_(context) {
  VkCommandBufferAllocateInfo info{VK_STRUCTURE_TYPE_COMMAND_BUFFER_ALLOCATE_INFO};
  info.commandPool = context_.command_pool();
  info.level = VK_COMMAND_BUFFER_LEVEL_PRIMARY;
  info.commandBufferCount = 1;
  vk_check(vkAllocateCommandBuffers(context_.device(), &info, &commands_),
           "vkAllocateCommandBuffers");
  VkFenceCreateInfo fence_info{VK_STRUCTURE_TYPE_FENCE_CREATE_INFO};
  vk_check(vkCreateFence(context_.device(), &fence_info, nullptr, &fence_), "vkCreateFence");
  if (context_.timestamp_period_ns() > 0) {
    VkQueryPoolCreateInfo query_info{VK_STRUCTURE_TYPE_QUERY_POOL_CREATE_INFO};
    query_info.queryType = VK_QUERY_TYPE_TIMESTAMP;
    query_info.queryCount = kMaxTimestamps;
    vk_check(vkCreateQueryPool(context_.device(), &query_info, nullptr, &queries_),
             "vkCreateQueryPool");
  }
}

CommandBatch::~CommandBatch() {
  VkDevice device = context_.device();
  if (recording_) vkEndCommandBuffer(commands_);
  for (VkDescriptorPool pool : pools_) vkDestroyDescriptorPool(device, pool, nullptr);
  if (queries_) vkDestroyQueryPool(device, queries_, nullptr);
  vkDestroyFence(device, fence_, nullptr);
  vkFreeCommandBuffers(device, context_.command_pool(), 1, &commands_);
}

VkDescriptorSet CommandBatch::allocate_set(const Kernel& kernel) {
  // Pools of 64 sets each; a batch takes as many as it dispatches, all freed by run().
  constexpr uint32_t kSetsPerPool = 64, kBuffersPerSet = 20;
  for (;;) {
    if (pool_in_use_ == pools_.size()) {
      VkDescriptorPoolSize size{VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, kSetsPerPool * kBuffersPerSet};
      VkDescriptorPoolCreateInfo info{VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO};
      info.maxSets = kSetsPerPool;
      info.poolSizeCount = 1;
      info.pPoolSizes = &size;
      VkDescriptorPool pool = VK_NULL_HANDLE;
      vk_check(vkCreateDescriptorPool(context_.device(), &info, nullptr, &pool),
               "vkCreateDescriptorPool");
      pools_.push_back(pool);
    }
    VkDescriptorSetLayout layout = kernel.set_layout();
    VkDescriptorSetAllocateInfo info{VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO};
    info.descriptorPool = pools_[pool_in_use_];
    info.descriptorSetCount = 1;
    info.pSetLayouts = &layout;
    VkDescriptorSet set = VK_NULL_HANDLE;
    const VkResult r = vkAllocateDescriptorSets(context_.device(), &info, &set);
    if (r == VK_SUCCESS) return set;
    if (r != VK_ERROR_OUT_OF_POOL_MEMORY && r != VK_ERROR_FRAGMENTED_POOL) {
      vk_check(r, "vkAllocateDescriptorSets");
    }
    ++pool_in_use_;
  }
}

void CommandBatch::begin_recording() {
  if (recording_) return;
  VkCommandBufferBeginInfo begin{VK_STRUCTURE_TYPE_COMMAND_BUFFER_BEGIN_INFO};
  begin.flags = VK_COMMAND_BUFFER_USAGE_ONE_TIME_SUBMIT_BIT;
  vk_check(vkBeginCommandBuffer(commands_, &begin), "vkBeginCommandBuffer");
  recording_ = true;
  timed_.clear();
  if (queries_) {
    vkCmdResetQueryPool(commands_, queries_, 0, kMaxTimestamps);
    vkCmdWriteTimestamp(commands_, VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, queries_, 0);
  }
}

void CommandBatch::barrier() {
  VkMemoryBarrier b{VK_STRUCTURE_TYPE_MEMORY_BARRIER};
  b.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT | VK_ACCESS_TRANSFER_WRITE_BIT;
  b.dstAccessMask = VK_ACCESS_SHADER_READ_BIT | VK_ACCESS_SHADER_WRITE_BIT |
                    VK_ACCESS_TRANSFER_READ_BIT | VK_ACCESS_TRANSFER_WRITE_BIT |
                    VK_ACCESS_HOST_READ_BIT;
  const VkPipelineStageFlags stages =
      VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT | VK_PIPELINE_STAGE_TRANSFER_BIT;
  vkCmdPipelineBarrier(commands_, stages, stages | VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &b, 0, nullptr,
                       0, nullptr);
}

void CommandBatch::dispatch(const Kernel& kernel, std::initializer_list<const Buffer*> buffers,
                            std::initializer_list<uint32_t> push, uint32_t groups_x,
                            uint32_t groups_y) {
  if (buffers.size() != kernel.bindings()) {
    throw Error(std::string("vulkan: ") + kernel.name() + " binds " +
                std::to_string(kernel.bindings()) + " buffers, got " +
                std::to_string(buffers.size()));
  }
  if (push.size() > Kernel::kPushBytes / 4) {
    throw Error(std::string("vulkan: ") + kernel.name() + " given " + std::to_string(push.size()) +
                " push constants, at most " + std::to_string(Kernel::kPushBytes / 4));
  }
  if (groups_x == 0 || groups_y == 0) return;
  begin_recording();
  const VkDescriptorSet set = allocate_set(kernel);
  std::vector<VkDescriptorBufferInfo> infos;
  infos.reserve(buffers.size());
  for (const Buffer* b : buffers) infos.push_back({b->handle(), 0, VK_WHOLE_SIZE});
  std::vector<VkWriteDescriptorSet> writes(buffers.size());
  for (std::size_t i = 0; i < writes.size(); ++i) {
    writes[i] = {VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET};
    writes[i].dstSet = set;
    writes[i].dstBinding = static_cast<uint32_t>(i);
    writes[i].descriptorCount = 1;
    writes[i].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
    writes[i].pBufferInfo = &infos[i];
  }
  vkUpdateDescriptorSets(context_.device(), static_cast<uint32_t>(writes.size()), writes.data(), 0,
                         nullptr);
  vkCmdBindPipeline(commands_, VK_PIPELINE_BIND_POINT_COMPUTE, kernel.pipeline());
  vkCmdBindDescriptorSets(commands_, VK_PIPELINE_BIND_POINT_COMPUTE, kernel.layout(), 0, 1, &set, 0,
                          nullptr);
  uint32_t values[Kernel::kPushBytes / 4] = {};
  std::size_t k = 0;
  for (uint32_t v : push) values[k++] = v;
  vkCmdPushConstants(commands_, kernel.layout(), VK_SHADER_STAGE_COMPUTE_BIT, 0, Kernel::kPushBytes,
                     values);
  vkCmdDispatch(commands_, groups_x, groups_y, 1);
  barrier();
  if (queries_ && timed_.size() + 1 < kMaxTimestamps) {
    timed_.push_back(kernel.name());
    vkCmdWriteTimestamp(commands_, VK_PIPELINE_STAGE_BOTTOM_OF_PIPE_BIT, queries_,
                        static_cast<uint32_t>(timed_.size()));
  }
}

namespace {

// Throws unless [offset, offset + bytes) lies inside the buffer.
void check_range(const Buffer& buffer, std::size_t bytes, std::size_t offset, const char* what) {
  if (offset > buffer.capacity() || bytes > buffer.capacity() - offset) {
    throw Error(std::string("vulkan: ") + what + " of " + std::to_string(bytes) + " bytes at offset " +
                std::to_string(offset) + " into a buffer of " + std::to_string(buffer.capacity()));
  }
}

}  // namespace

void CommandBatch::fill_zero(Buffer& buffer, std::size_t bytes, std::size_t offset) {
  if (bytes == 0) return;
  check_range(buffer, (bytes + 3) / 4 * 4, offset, "fill");
  begin_recording();
  vkCmdFillBuffer(commands_, buffer.handle(), offset, (bytes + 3) / 4 * 4, 0);
  barrier();
}

void CommandBatch::copy(const Buffer& from, Buffer& to, std::size_t bytes, std::size_t from_offset,
                        std::size_t to_offset) {
  if (bytes == 0) return;
  check_range(from, bytes, from_offset, "copy");
  check_range(to, bytes, to_offset, "copy");
  begin_recording();
  const VkBufferCopy region{from_offset, to_offset, bytes};
  vkCmdCopyBuffer(commands_, from.handle(), to.handle(), 1, &region);
  barrier();
}

void CommandBatch::upload(Buffer& buffer, const void* data, std::size_t bytes, std::size_t offset) {
  if (bytes == 0) return;
  check_range(buffer, bytes, offset, "upload");
  uploaded_bytes_ += bytes;
  if (buffer.mapped()) {
    std::memcpy(static_cast<char*>(buffer.mapped()) + offset, data, bytes);
    return;
  }
  Buffer& staging = next_staging(bytes);
  std::memcpy(staging.mapped(), data, bytes);
  copy(staging, buffer, bytes, 0, offset);
}

void CommandBatch::download(const Buffer& buffer, void* data, std::size_t bytes, std::size_t offset) {
  if (bytes == 0) return;
  check_range(buffer, bytes, offset, "download");
  downloaded_bytes_ += bytes;
  const Buffer* source = &buffer;
  std::size_t from = offset;
  if (!buffer.mapped()) {
    Buffer& staging = next_staging(bytes);
    copy(buffer, staging, bytes, offset, 0);
    source = &staging;
    from = 0;
  }
  after_run_.push_back([source, data, bytes, from] {
    std::memcpy(data, static_cast<const char*>(source->mapped()) + from, bytes);
  });
}

Buffer& CommandBatch::next_staging(std::size_t bytes) {
  if (staging_used_ == staging_.size()) staging_.push_back(std::make_unique<Buffer>(context_));
  Buffer& staging = *staging_[staging_used_++];
  staging.reserve_staging(bytes);
  return staging;
}

void CommandBatch::discard() {
  if (recording_) {
    vk_check(vkEndCommandBuffer(commands_), "vkEndCommandBuffer");
    vk_check(vkResetCommandBuffer(commands_, 0), "vkResetCommandBuffer");
    recording_ = false;
  }
  timed_.clear();
  after_run_.clear();
  staging_used_ = 0;
  for (VkDescriptorPool pool : pools_) vkResetDescriptorPool(context_.device(), pool, 0);
  pool_in_use_ = 0;
}

void CommandBatch::run() {
  if (recording_) {
    vk_check(vkEndCommandBuffer(commands_), "vkEndCommandBuffer");
    recording_ = false;
    VkSubmitInfo submit{VK_STRUCTURE_TYPE_SUBMIT_INFO};
    submit.commandBufferCount = 1;
    submit.pCommandBuffers = &commands_;
    vk_check(vkQueueSubmit(context_.queue(), 1, &submit, fence_), "vkQueueSubmit");
    vk_check(vkWaitForFences(context_.device(), 1, &fence_, VK_TRUE, UINT64_MAX),
             "vkWaitForFences");
    vk_check(vkResetFences(context_.device(), 1, &fence_), "vkResetFences");
    vk_check(vkResetCommandBuffer(commands_, 0), "vkResetCommandBuffer");
    if (queries_ && !timed_.empty()) {
      std::vector<uint64_t> ticks(timed_.size() + 1);
      vk_check(
          vkGetQueryPoolResults(context_.device(), queries_, 0, static_cast<uint32_t>(ticks.size()),
                                ticks.size() * sizeof(uint64_t), ticks.data(), sizeof(uint64_t),
                                VK_QUERY_RESULT_64_BIT | VK_QUERY_RESULT_WAIT_BIT),
          "vkGetQueryPoolResults");
      // Each dispatch's time: from the previous timestamp (transfers in between count too).
      for (std::size_t k = 0; k < timed_.size(); ++k) {
        kernel_ms_[timed_[k]] +=
            double(ticks[k + 1] - ticks[k]) * context_.timestamp_period_ns() * 1e-6;
      }
    }
  }
  for (auto& copy_out : after_run_) copy_out();
  after_run_.clear();
  staging_used_ = 0;
  for (VkDescriptorPool pool : pools_) vkResetDescriptorPool(context_.device(), pool, 0);
  pool_in_use_ = 0;
}

}  // namespace splat::vk
