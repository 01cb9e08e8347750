#version 450
// Exclusive prefix sum, second level: adds each block's scanned offset to its kScanBlock
// elements. One invocation per element. Deterministic.
#extension GL_GOOGLE_include_directive : require
#include "shader_io.h"

layout(local_size_x = 256) in;
layout(std430, binding = 0) buffer Data { uint data[]; };
layout(std430, binding = 1) readonly buffer BlockSums { uint block_sums[]; };
layout(push_constant) uniform Push { uint count; } push;

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i < push.count) data[i] += block_sums[i / kScanBlock];
}
