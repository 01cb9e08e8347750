#include "vulkan/device_sort.h"

#include <utility>

#include "radix_histogram_spv.h"
#include "radix_scatter_spv.h"
#include "scan_add_spv.h"
#include "scan_blocks_spv.h"
#include "shader_io.h"
#include "splat/error.h"

namespace splat::vk {
namespace {

uint32_t ceil_div(uint32_t a, uint32_t b) { return (a + b - 1) / b; }

}  // namespace

PrefixSum::PrefixSum(Context& context)
    : context_(context),
      blocks_(context, kScanBlocksSpv, 2, "scan_blocks"),
      add_(context, kScanAddSpv, 2, "scan_add") {}

void PrefixSum::prepare(uint32_t count) {
  std::size_t level = 0;
  do {
    count = ceil_div(count, io::kScanBlock);
    if (levels_.size() <= level) levels_.emplace_back(context_);
    levels_[level].reserve(std::size_t(count) * 4);
    ++level;
  } while (count > 1);
}

void PrefixSum::record(CommandBatch& batch, Buffer& data, uint32_t count, Buffer* total) {
  if (count == 0) {
    if (total) batch.fill_zero(*total, 4);
    return;
  }
  record_level(batch, data, count, 0, total);
}

void PrefixSum::record_level(CommandBatch& batch, Buffer& data, uint32_t count, std::size_t level,
                             Buffer* total) {
  const uint32_t groups = ceil_div(count, io::kScanBlock);
  if (level >= levels_.size() || levels_[level].capacity() < std::size_t(groups) * 4) {
    throw Error("vulkan: prefix sum of " + std::to_string(count) + " elements was not prepared");
  }
  Buffer& sums = levels_[level];
  batch.dispatch(blocks_, {&data, &sums}, {count}, groups);
  if (groups > 1) {
    record_level(batch, sums, groups, level + 1, total);
    batch.dispatch(add_, {&data, &sums}, {count}, ceil_div(count, io::kGroupSize));
  } else if (total) {
    batch.copy(sums, *total, 4);
  }
}

RadixSort::RadixSort(Context& context, PrefixSum& scan)
    : scan_(scan),
      histogram_(context, kRadixHistogramSpv, 2, "radix_histogram"),
      scatter_(context, kRadixScatterSpv, 5, "radix_scatter"),
      counts_(context) {}

uint32_t RadixSort::passes(uint32_t key_bits) { return ceil_div(key_bits, io::kRadixBits); }
uint32_t RadixSort::blocks(uint32_t count) { return ceil_div(count, io::kGroupSize); }

void RadixSort::prepare(uint32_t count) {
  const uint32_t digits = blocks(count) * io::kRadixBins;
  counts_.reserve(std::size_t(digits) * 4);
  scan_.prepare(digits);
}

bool RadixSort::record(CommandBatch& batch, Buffer& keys, Buffer& values, Buffer& keys_tmp,
                       Buffer& values_tmp, uint32_t count, uint32_t key_bits) {
  const uint32_t block_count = blocks(count);
  if (counts_.capacity() < std::size_t(block_count) * io::kRadixBins * 4) {
    throw Error("vulkan: radix sort of " + std::to_string(count) + " keys was not prepared");
  }
  Buffer* src_keys = &keys;
  Buffer* src_values = &values;
  Buffer* dst_keys = &keys_tmp;
  Buffer* dst_values = &values_tmp;
  const uint32_t pass_count = count > 1 ? passes(key_bits) : 0;
  for (uint32_t pass = 0; pass < pass_count; ++pass) {
    const uint32_t shift = pass * io::kRadixBits;
    batch.dispatch(histogram_, {src_keys, &counts_}, {count, shift, block_count}, block_count);
    scan_.record(batch, counts_, block_count * io::kRadixBins, nullptr);
    batch.dispatch(scatter_, {src_keys, src_values, dst_keys, dst_values, &counts_},
                   {count, shift, block_count}, block_count);
    std::swap(src_keys, dst_keys);
    std::swap(src_values, dst_values);
  }
  return pass_count % 2 == 1;
}

}  // namespace splat::vk
