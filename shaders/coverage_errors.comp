#version 450
// Densification's coverage test, first stage: per pixel the render's depth error where the
// render covers a measured pixel (alpha above the limit), as float bits (errors are >= 0, so
// their bits sort as they do), and 0xffffffff where there is none; counts the errors in
// select[0] (zeroed beforehand), whose median coverage_select.comp then finds.
#extension GL_GOOGLE_include_directive : require
#include "shader_io.h"

layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer Alpha { float alpha[]; };               // [H, W]
layout(std430, binding = 1) readonly buffer RenderDepth { float depth_normalized[]; };  // [H, W]
layout(std430, binding = 2) readonly buffer Depth { float depth[]; };               // [H, W], 0 = none
layout(std430, binding = 3) buffer Keys { uint keys[]; };                           // [H, W]
layout(std430, binding = 4) buffer Select { uint select_state[]; };                 // kCoverageSelectWords
layout(push_constant) uniform Push { uint pixels; uint densify_alpha; } push;

void main() {
  uint p = gl_GlobalInvocationID.x;
  if (p >= push.pixels) return;
  uint key = kCoverageNoError;
  if (depth[p] > 0.0 && alpha[p] > uintBitsToFloat(push.densify_alpha)) {
    precise float error = abs(depth_normalized[p] - depth[p]);
    key = floatBitsToUint(error);
    atomicAdd(select_state[kCoverageCount], 1u);
  }
  keys[p] = key;
}
