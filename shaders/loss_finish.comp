#version 450
// Mapping loss, the gradient w.r.t. the radiance: one invocation per pixel, kGroupSize pixels
// per workgroup. Adds the blurred SSIM gradient (d/dx of mu_x, E[x^2], E[xy]) to the L1
// gradient in d_rgb, both w.r.t. the recorded colour, then goes back through the vignetting:
// dL/d(gain) = sum_c dL/d(recorded_c) rgb_c, d_rgb = dL/d(recorded) * gain, and the workgroup's
// sums of dL/d(gain) r^2 and dL/d(gain) r^4 (dL/dk1, dL/dk2) in a fixed tree. Reads 1..4,
// updates 5, writes 6. Deterministic.
#extension GL_GOOGLE_include_directive : require
#include "loss_pixel.glsl"

layout(local_size_x = 256) in;
layout(std430, binding = 1) readonly buffer Rgb { float rgb[]; };               // [H, W, 3]
layout(std430, binding = 2) readonly buffer TargetRgb { float target_rgb[]; };  // [H, W, 3]
layout(std430, binding = 3) readonly buffer Ignore { uint ignore[]; };          // [H, W]
layout(std430, binding = 4) readonly buffer Grads { float grads[]; };  // [3 * kSsimGrads, H, W]
layout(std430, binding = 5) buffer DRgb { float d_rgb[]; };            // [H, W, 3]
layout(std430, binding = 6) buffer Partials { double partials[]; };   // [groups, kLossPartials]

shared double reduction[2][kGroupSize];

void main() {
  uint p = gl_GlobalInvocationID.x;
  uint tid = gl_LocalInvocationID.x;
  uint pixels = pixel_count();
  double d_k1 = 0.0lf, d_k2 = 0.0lf;
  if (p < pixels) {
    double r2 = radius2(p);
    float gain = vignetting_gain(r2);
    bool ignored = params.has_ignore != 0u && ignore[p] != 0u;
    double d_gain = 0.0lf;  // dL/d(gain) at this pixel
    for (uint c = 0u; c < 3u; ++c) {
      uint i = p * 3u + c;
      float radiance = rgb[i];
      float d = d_rgb[i];  // dL/d(recorded), the L1 part
      if (params.ssim != 0u) {
        float x = radiance * gain;
        float y = ignored ? x : target_rgb[i];
        uint plane = c * kSsimGrads;
        d += grads[plane * pixels + p] + 2 * x * grads[(plane + 1u) * pixels + p] +
             y * grads[(plane + 2u) * pixels + p];
      }
      d_gain += double(d) * double(radiance);
      d_rgb[i] = d * gain;
    }
    d_k1 = d_gain * r2;
    d_k2 = d_gain * r2 * r2;
  }
  reduction[0][tid] = d_k1;
  reduction[1][tid] = d_k2;
  barrier();
  for (uint half_size = kGroupSize / 2u; half_size > 0u; half_size >>= 1) {
    if (tid < half_size) {
      reduction[0][tid] += reduction[0][tid + half_size];
      reduction[1][tid] += reduction[1][tid + half_size];
    }
    barrier();
  }
  if (tid == 0u) {
    partials[gl_WorkGroupID.x * kLossPartials + kLossVignetteK1] = reduction[0][0];
    partials[gl_WorkGroupID.x * kLossPartials + kLossVignetteK2] = reduction[1][0];
  }
}
