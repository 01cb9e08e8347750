#version 450
// Pruning's test on the device: bit i is set where Gaussian i is faint (opacity logit below the
// limit) or oversized (its largest log scale above the limit). Words zeroed beforehand.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer LogScales { float log_scales[]; };  // [N, 3]
layout(std430, binding = 1) readonly buffer Opacity { float opacity_logits[]; }; // [N]
layout(std430, binding = 2) buffer Flags { uint flags[]; };                      // [ceil(N / 32)]
layout(push_constant) uniform Push { uint count; uint min_opacity_logit; uint max_log_scale; } push;

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= push.count) return;
  float largest = max(max(log_scales[3u * i], log_scales[3u * i + 1u]), log_scales[3u * i + 2u]);
  if (opacity_logits[i] < uintBitsToFloat(push.min_opacity_logit) || largest > uintBitsToFloat(push.max_log_scale)) {
    atomicOr(flags[i >> 5], 1u << (i & 31u));
  }
}
