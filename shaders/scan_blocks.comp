#version 450
// Exclusive prefix sum, first level: one workgroup scans kScanBlock uints in place (4 per
// invocation) and writes its block total to block_sums[workgroup]. The host scans the block
// totals the same way and adds them back with scan_add.comp. Deterministic.
#extension GL_GOOGLE_include_directive : require
#include "shader_io.h"

layout(local_size_x = 256) in;
layout(std430, binding = 0) buffer Data { uint data[]; };
layout(std430, binding = 1) writeonly buffer BlockSums { uint block_sums[]; };
layout(push_constant) uniform Push { uint count; } push;

shared uint partial[256];

void main() {
  uint tid = gl_LocalInvocationID.x;
  uint base = gl_WorkGroupID.x * kScanBlock + tid * 4u;
  uint v[4];
  uint sum = 0;
  for (uint k = 0; k < 4u; ++k) {
    v[k] = base + k < push.count ? data[base + k] : 0u;
    uint here = v[k];
    v[k] = sum;  // exclusive within the invocation
    sum += here;
  }
  // Hillis-Steele inclusive scan of the invocation totals.
  partial[tid] = sum;
  barrier();
  for (uint offset = 1u; offset < 256u; offset <<= 1) {
    uint add = tid >= offset ? partial[tid - offset] : 0u;
    barrier();
    partial[tid] += add;
    barrier();
  }
  uint before = partial[tid] - sum;
  for (uint k = 0; k < 4u; ++k) {
    if (base + k < push.count) data[base + k] = before + v[k];
  }
  if (tid == 255u) block_sums[gl_WorkGroupID.x] = partial[255];
}
