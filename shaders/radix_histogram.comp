#version 450
// Radix sort pass, step 1: one workgroup counts the kRadixBins digits (bits shift..shift+3) of
// its kGroupSize keys and writes them digit-major, histogram[digit * blocks + block], so one
// exclusive scan of the whole array gives every block's output offset per digit.
#extension GL_GOOGLE_include_directive : require
#include "shader_io.h"

layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer Keys { uint keys[]; };
layout(std430, binding = 1) writeonly buffer Histogram { uint histogram[]; };
layout(push_constant) uniform Push { uint count; uint shift; uint blocks; } push;

shared uint bins[kRadixBins];

void main() {
  uint tid = gl_LocalInvocationID.x;
  if (tid < kRadixBins) bins[tid] = 0u;
  barrier();
  uint i = gl_GlobalInvocationID.x;
  if (i < push.count) atomicAdd(bins[(keys[i] >> push.shift) & (kRadixBins - 1u)], 1u);
  barrier();
  if (tid < kRadixBins) histogram[tid * push.blocks + gl_WorkGroupID.x] = bins[tid];
}
