#version 450
// Densification's coverage test, last stage: bit p is set where pixel p should be seeded,
// uncovered (alpha below the limit) or measured in front of the render by more than
// depth_error_factor x the median error (at least min_median), and not ignored. In float, as
// the host's test computes it (mapping/src/mapper.cpp). Words zeroed beforehand.
#extension GL_GOOGLE_include_directive : require
#include "shader_io.h"

layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer Alpha { float alpha[]; };               // [H, W]
layout(std430, binding = 1) readonly buffer RenderDepth { float depth_normalized[]; };  // [H, W]
layout(std430, binding = 2) readonly buffer Depth { float depth[]; };               // [H, W], 0 = none
layout(std430, binding = 3) readonly buffer Ignore { uint ignore[]; };              // [H, W] when has_ignore
layout(std430, binding = 4) readonly buffer Select { uint select_state[]; };        // kCoverageSelectWords
layout(std430, binding = 5) buffer Mask { uint mask[]; };                           // [ceil(H W / 32)]
// Four words at most: the pixel count carries in its top bit whether the ignore mask is bound.
layout(push_constant) uniform Push {
  uint pixels_and_has_ignore;
  uint densify_alpha;
  uint depth_error_factor;
  uint min_median;
} push;

void main() {
  uint p = gl_GlobalInvocationID.x;
  if (p >= (push.pixels_and_has_ignore & 0x7fffffffu)) return;
  float median = select_state[kCoverageCount] == 0u ? 0.0 : uintBitsToFloat(select_state[kCoveragePrefix]);
  precise float threshold = uintBitsToFloat(push.depth_error_factor) * max(median, uintBitsToFloat(push.min_median));
  bool uncovered = alpha[p] < uintBitsToFloat(push.densify_alpha);
  precise float in_front_by = depth_normalized[p] - depth[p];
  bool in_front = depth[p] > 0.0 && in_front_by > threshold;
  bool ignored = (push.pixels_and_has_ignore & 0x80000000u) != 0u && ignore[p] != 0u;
  if ((uncovered || in_front) && !ignored) atomicOr(mask[p >> 5], 1u << (p & 31u));
}
