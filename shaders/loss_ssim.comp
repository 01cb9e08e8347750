#version 450
// Mapping loss, the SSIM terms: one invocation per pixel (its three channels), kGroupSize
// pixels per workgroup. From the blurred statistics mu_x, mu_y, E[x^2], E[y^2], E[xy] it writes
// dLoss/d(mu_x), dLoss/d(E[x^2]), dLoss/d(E[xy]) (losses.cpp's da, db, dc, in float as there)
// and the workgroup's sum of 1 - SSIM in a fixed tree. Reads 1, writes 2..3. Deterministic.
#extension GL_GOOGLE_include_directive : require
#include "loss_pixel.glsl"

layout(local_size_x = 256) in;
layout(std430, binding = 1) readonly buffer Stats { float stats[]; };  // [3 * kSsimStats, H, W]
layout(std430, binding = 2) writeonly buffer Grads { float grads[]; }; // [3 * kSsimGrads, H, W]
layout(std430, binding = 3) buffer Partials { double partials[]; };    // [groups, kLossPartials]

shared double reduction[kGroupSize];

// C1 = 0.01^2, C2 = 0.03^2 rounded to float from double, as losses.cpp does.
const float kC1 = float(0.01lf * 0.01lf), kC2 = float(0.03lf * 0.03lf);

void main() {
  uint p = gl_GlobalInvocationID.x;
  uint tid = gl_LocalInvocationID.x;
  uint pixels = pixel_count();
  double dssim = 0.0lf;
  if (p < pixels) {
    float scale = params.ssim_scale;
    for (uint c = 0u; c < 3u; ++c) {
      uint plane = c * kSsimStats;
      float mx = stats[(plane + 0u) * pixels + p], my = stats[(plane + 1u) * pixels + p];
      float exx = stats[(plane + 2u) * pixels + p], eyy = stats[(plane + 3u) * pixels + p];
      float exy = stats[(plane + 4u) * pixels + p];
      float a1 = 2 * mx * my + kC1, a2 = 2 * (exy - mx * my) + kC2;
      float b1 = mx * mx + my * my + kC1;
      float b2 = exx - mx * mx + eyy - my * my + kC2;
      float inv_b = 1 / (b1 * b2);
      float s = a1 * a2 * inv_b;
      dssim += 1.0lf - double(s);
      // Not divided by a1 or a2: a2 can be exactly 0 (see losses.cpp).
      uint out_plane = c * kSsimGrads;
      grads[(out_plane + 0u) * pixels + p] =
          -scale * (2 * my * (a2 - a1) * inv_b + s * (2 * mx / b2 - 2 * mx / b1));
      grads[(out_plane + 1u) * pixels + p] = -scale * s * (-1 / b2);
      grads[(out_plane + 2u) * pixels + p] = -scale * 2 * a1 * inv_b;
    }
  }
  reduction[tid] = dssim;
  barrier();
  for (uint half_size = kGroupSize / 2u; half_size > 0u; half_size >>= 1) {
    if (tid < half_size) reduction[tid] += reduction[tid + half_size];
    barrier();
  }
  if (tid == 0u) partials[gl_WorkGroupID.x * kLossPartials + kLossDssim] = reduction[0];
}
