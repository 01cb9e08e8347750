// GPU prefix sum and stable LSD radix sort of (uint key, uint value) pairs, kRadixBits per pass.
// Scratch memory is reserved by prepare() before a batch is recorded, never during it, so no
// buffer a recorded command refers to is reallocated.
#pragma once
#include <cstdint>
#include <vector>

#include "vulkan/compute.h"

namespace splat::vk {

class PrefixSum {
 public:
  explicit PrefixSum(Context& context);
  // Reserves scratch for scans of up to `count` elements.
  void prepare(uint32_t count);
  // Exclusive scan of data[0, count) in place; if `total` is given, copies the sum to total[0].
  void record(CommandBatch& batch, Buffer& data, uint32_t count, Buffer* total);

 private:
  void record_level(CommandBatch& batch, Buffer& data, uint32_t count, std::size_t level,
                    Buffer* total);

  Context& context_;
  Kernel blocks_, add_;
  std::vector<Buffer> levels_;  // block sums of each level
};

class RadixSort {
 public:
  RadixSort(Context& context, PrefixSum& scan);
  // Reserves scratch for sorts of up to `count` pairs (also prepares the prefix sum).
  void prepare(uint32_t count);
  // Stable sort of pairs [0, count) by the low `key_bits` bits of the keys, ping-ponging
  // between (keys, values) and (keys_tmp, values_tmp). Returns true when the result ended in
  // the _tmp pair (an odd number of passes).
  bool record(CommandBatch& batch, Buffer& keys, Buffer& values, Buffer& keys_tmp,
              Buffer& values_tmp, uint32_t count, uint32_t key_bits);

  static uint32_t passes(uint32_t key_bits);
  static uint32_t blocks(uint32_t count);

 private:
  PrefixSum& scan_;
  Kernel histogram_, scatter_;
  Buffer counts_;  // [kRadixBins, blocks], digit-major
};

}  // namespace splat::vk
