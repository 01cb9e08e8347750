#version 450
// Mapping loss, pointwise terms: one invocation per pixel, kGroupSize pixels per workgroup.
// Records the render through the vignetting, replaces the targets of ignored pixels (colour:
// the recorded render, depth: none), and writes the L1 colour gradient (w.r.t. the recorded
// colour, into d_rgb), the silhouette depth gradients (d_depth, d_alpha) and, when D-SSIM is
// on, its statistics planes [3 channels x kSsimStats, H, W]. Partial sums of |residual| per
// workgroup in a fixed tree. Reads 0..6, writes 7..11. Deterministic.
#extension GL_GOOGLE_include_directive : require
#include "loss_pixel.glsl"

layout(local_size_x = 256) in;
layout(std430, binding = 1) readonly buffer Rgb { float rgb[]; };                  // [H, W, 3]
layout(std430, binding = 2) readonly buffer Alpha { float alpha[]; };              // [H, W]
layout(std430, binding = 3) readonly buffer Depth { float depth[]; };              // [H, W]
layout(std430, binding = 4) readonly buffer TargetRgb { float target_rgb[]; };     // [H, W, 3]
layout(std430, binding = 5) readonly buffer TargetDepth { float target_depth[]; }; // [H, W]
layout(std430, binding = 6) readonly buffer Ignore { uint ignore[]; };             // [H, W]
layout(std430, binding = 7) writeonly buffer DRgb { float d_rgb[]; };              // [H, W, 3]
layout(std430, binding = 8) writeonly buffer DAlpha { float d_alpha[]; };          // [H, W]
layout(std430, binding = 9) writeonly buffer DDepth { float d_depth[]; };          // [H, W]
layout(std430, binding = 10) writeonly buffer Stats { float stats[]; };  // [3 * kSsimStats, H, W]
layout(std430, binding = 11) buffer Partials { double partials[]; };     // [groups, kLossPartials]

shared double reduction[2][kGroupSize];

void main() {
  uint p = gl_GlobalInvocationID.x;
  uint tid = gl_LocalInvocationID.x;
  uint pixels = pixel_count();
  double color_l1 = 0.0lf, depth_l1 = 0.0lf;
  if (p < pixels) {
    float gain = vignetting_gain(radius2(p));
    bool ignored = params.has_ignore != 0u && ignore[p] != 0u;
    for (uint c = 0u; c < 3u; ++c) {
      float x = rgb[p * 3u + c] * gain;  // what the camera records
      float y = ignored ? x : target_rgb[p * 3u + c];
      double r = double(x) - double(y);
      color_l1 += abs(r);
      d_rgb[p * 3u + c] = float(params.color_scale * double(sign_of(r)));
      if (params.ssim != 0u) {
        uint plane = c * kSsimStats;
        stats[(plane + 0u) * pixels + p] = x;
        stats[(plane + 1u) * pixels + p] = y;
        stats[(plane + 2u) * pixels + p] = x * x;
        stats[(plane + 3u) * pixels + p] = y * y;
        stats[(plane + 4u) * pixels + p] = x * y;
      }
    }
    // Silhouette depth L1: D / A where A > threshold, else D (see losses.h).
    float measured = ignored ? 0.0 : target_depth[p];
    float g_depth = 0.0, g_alpha = 0.0;
    if (measured > 0.0) {
      double a = double(alpha[p]);
      bool normalized = a > params.alpha_threshold;
      double pred = normalized ? double(depth[p]) / a : double(depth[p]);
      double r = pred - double(measured);
      double g = params.depth_scale * double(sign_of(r));
      depth_l1 = abs(r);
      if (normalized) {  // d(D/A)/dD = 1/A, d(D/A)/dA = -(D/A)/A
        g_depth = float(g / a);
        g_alpha = -float(g * pred / a);
      } else {
        g_depth = float(g);
      }
    }
    d_depth[p] = g_depth;
    d_alpha[p] = g_alpha;
  }
  reduction[0][tid] = color_l1;
  reduction[1][tid] = depth_l1;
  barrier();
  for (uint half_size = kGroupSize / 2u; half_size > 0u; half_size >>= 1) {
    if (tid < half_size) {
      reduction[0][tid] += reduction[0][tid + half_size];
      reduction[1][tid] += reduction[1][tid + half_size];
    }
    barrier();
  }
  if (tid == 0u) {
    partials[gl_WorkGroupID.x * kLossPartials + kLossColorL1] = reduction[0][0];
    partials[gl_WorkGroupID.x * kLossPartials + kLossDepthL1] = reduction[1][0];
  }
}
