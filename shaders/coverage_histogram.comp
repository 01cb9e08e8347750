#version 450
// Densification's median by radix selection, one pass of kCoverageBits bits from the top: counts
// the errors whose higher bits match the prefix chosen so far (select[kCoveragePrefix]) by their
// next kCoverageBits bits into the histogram (zeroed beforehand).
#extension GL_GOOGLE_include_directive : require
#include "shader_io.h"

layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer Keys { uint keys[]; };           // [H, W]
layout(std430, binding = 1) readonly buffer Select { uint select_state[]; };  // kCoverageSelectWords
layout(std430, binding = 2) buffer Histogram { uint histogram[]; };         // [kCoverageBins]
layout(push_constant) uniform Push { uint pixels; uint shift; } push;

shared uint local_histogram[kCoverageBins];

void main() {
  uint t = gl_LocalInvocationID.x;
  for (uint b = t; b < kCoverageBins; b += gl_WorkGroupSize.x) local_histogram[b] = 0u;
  barrier();
  uint p = gl_GlobalInvocationID.x;
  if (p < push.pixels) {
    uint key = keys[p];
    // The bits above this pass's: all of them chosen already (none on the first pass).
    uint above = push.shift + kCoverageBits >= 32u ? 0u : ~((1u << (push.shift + kCoverageBits)) - 1u);
    if (key != kCoverageNoError && (key & above) == select_state[kCoveragePrefix]) {
      atomicAdd(local_histogram[(key >> push.shift) & (kCoverageBins - 1u)], 1u);
    }
  }
  barrier();
  for (uint b = t; b < kCoverageBins; b += gl_WorkGroupSize.x) {
    if (local_histogram[b] != 0u) atomicAdd(histogram[b], local_histogram[b]);
  }
}
