#version 450
// Radix sort pass, step 2: one invocation per key moves (key, value) to its digit's scanned
// block offset plus its rank among the block's earlier keys with the same digit, so the pass
// is stable and the sort is deterministic. The ranks come from one workgroup scan of 16
// counters packed two per uint (16 bits each; a block has at most 256 keys).
#extension GL_GOOGLE_include_directive : require
#include "shader_io.h"

layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer KeysIn { uint keys_in[]; };
layout(std430, binding = 1) readonly buffer ValuesIn { uint values_in[]; };
layout(std430, binding = 2) writeonly buffer KeysOut { uint keys_out[]; };
layout(std430, binding = 3) writeonly buffer ValuesOut { uint values_out[]; };
layout(std430, binding = 4) readonly buffer Offsets { uint offsets[]; };  // scanned histogram
layout(push_constant) uniform Push { uint count; uint shift; uint blocks; } push;

shared uvec4 counts_lo[256];  // digits 0..7, two per component
shared uvec4 counts_hi[256];  // digits 8..15

void main() {
  uint tid = gl_LocalInvocationID.x;
  uint i = gl_GlobalInvocationID.x;
  bool valid = i < push.count;
  uint key = valid ? keys_in[i] : 0u;
  uint digit = (key >> push.shift) & (kRadixBins - 1u);
  uvec4 own_lo = uvec4(0), own_hi = uvec4(0);
  if (valid) {
    uint one = 1u << ((digit & 1u) * 16u);
    uint component = (digit >> 1) & 3u;
    if (digit < 8u) own_lo[component] = one; else own_hi[component] = one;
  }
  counts_lo[tid] = own_lo;
  counts_hi[tid] = own_hi;
  barrier();
  for (uint offset = 1u; offset < 256u; offset <<= 1) {
    uvec4 add_lo = tid >= offset ? counts_lo[tid - offset] : uvec4(0);
    uvec4 add_hi = tid >= offset ? counts_hi[tid - offset] : uvec4(0);
    barrier();
    counts_lo[tid] += add_lo;
    counts_hi[tid] += add_hi;
    barrier();
  }
  if (!valid) return;
  uvec4 before = digit < 8u ? counts_lo[tid] - own_lo : counts_hi[tid] - own_hi;
  uint rank = (before[(digit >> 1) & 3u] >> ((digit & 1u) * 16u)) & 0xffffu;
  uint dst = offsets[digit * push.blocks + gl_WorkGroupID.x] + rank;
  keys_out[dst] = key;
  values_out[dst] = values_in[i];
}
