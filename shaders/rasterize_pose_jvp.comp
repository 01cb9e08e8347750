#version 450
// Per-pixel pose Jacobian of (r, g, b, depth, alpha): one workgroup per 16x16 tile, one
// invocation per pixel, walking the tile's splats front to back as the forward pass did, in
// forward mode: out = sum_j c_j a_j T_j, so d out = sum_j T_j (dc_j a_j + c_j da_j + c_j a_j
// dlogT_j) with dlogT_j = -sum_{k<j} da_k / (1 - a_k). Reads 0..9, writes 10
// ([H, W, 5, 6]). Deterministic.
#extension GL_GOOGLE_include_directive : require
#include "composite.glsl"

layout(local_size_x = 16, local_size_y = 16) in;
layout(std430, binding = 8) readonly buffer LastContributor { uint last_contributor[]; };  // [H, W]
layout(std430, binding = 9) readonly buffer ScreenJvp { float jvp[]; };  // [N, 9, 6]
layout(std430, binding = 10) writeonly buffer PoseJacobian { float jacobian[]; };  // [H, W, 5, 6]

const uint kJvpFloats = kScreenValues * 6u;
shared Splat batch[kBackwardBatch];
shared float batch_jvp[kBackwardBatch][kJvpFloats];
shared uint tile_last;

void main() {
  uint tid = gl_LocalInvocationIndex;
  uvec2 pixel = pixel_coord();
  bool inside = pixel_inside(pixel);
  vec2 centre = vec2(pixel) + 0.5;
  uint tile = tile_index();
  uint begin = tile_ranges[2 * tile];
  uint o = pixel.y * frame.width + pixel.x;
  uint last = inside ? last_contributor[o] : 0u;
  float trans = 1.0;
  float d_log_t[6], d_r[6], d_g[6], d_b[6], d_z[6];
  for (int k = 0; k < 6; ++k) d_log_t[k] = d_r[k] = d_g[k] = d_b[k] = d_z[k] = 0;
  if (tid == 0u) tile_last = 0u;
  barrier();
  atomicMax(tile_last, last);
  barrier();
  uint end = max(tile_last, begin);
  for (uint lo = begin; lo < end; lo += kBackwardBatch) {
    uint count = min(kBackwardBatch, end - lo);
    if (tid < count) batch[tid] = load_splat(sorted_ids[lo + tid]);
    for (uint item = tid; item < count * kJvpFloats; item += kGroupSize) {
      uint k = item / kJvpFloats, v = item % kJvpFloats;
      batch_jvp[k][v] = jvp[sorted_ids[lo + k] * kJvpFloats + v];
    }
    barrier();
    for (uint k = 0u; k < count; ++k) {
      uint s = lo + k;
      Splat sp = batch[k];
      PixelEval e = eval_pixel(sp, centre);
      float live = (s < last && e.alpha >= kAlphaMin) ? 1.0 : 0.0;
      if (live == 0) continue;
      float smooth_alpha = e.raw_alpha < kAlphaMax ? 1.0 : 0.0;
      float weight = e.alpha * trans;
      float inv = 1.0 / (1.0 - e.alpha);
      // dsigma/d(mean x, mean y, conic a, b, c) at this pixel.
      float ds[5] = float[5](sp.conic.x * e.dx + sp.conic.y * e.dy, sp.conic.z * e.dy + sp.conic.y * e.dx,
                             0.5 * e.dx * e.dx, e.dx * e.dy, 0.5 * e.dy * e.dy);
      for (uint d = 0u; d < 6u; ++d) {
        float d_sigma = 0;
        for (uint v = 0u; v < 5u; ++v) d_sigma += ds[v] * batch_jvp[k][v * 6u + d];
        float d_alpha = -smooth_alpha * e.raw_alpha * d_sigma;
        float d_weight = trans * (d_alpha + e.alpha * d_log_t[d]);
        d_r[d] += d_weight * sp.color.r + weight * batch_jvp[k][6u * 6u + d];
        d_g[d] += d_weight * sp.color.g + weight * batch_jvp[k][7u * 6u + d];
        d_b[d] += d_weight * sp.color.b + weight * batch_jvp[k][8u * 6u + d];
        d_z[d] += d_weight * sp.depth + weight * batch_jvp[k][5u * 6u + d];
        d_log_t[d] -= d_alpha * inv;
      }
      trans *= 1.0 - e.alpha;
    }
    barrier();
  }
  if (!inside) return;
  uint base = o * kPoseJacobianOutputs * 6u;
  vec3 bg = vec3(frame.background[0], frame.background[1], frame.background[2]);
  for (uint d = 0u; d < 6u; ++d) {
    float d_final = trans * d_log_t[d];  // d T_final
    jacobian[base + 0u * 6u + d] = d_r[d] + bg.r * d_final;
    jacobian[base + 1u * 6u + d] = d_g[d] + bg.g * d_final;
    jacobian[base + 2u * 6u + d] = d_b[d] + bg.b * d_final;
    jacobian[base + 3u * 6u + d] = d_z[d];
    jacobian[base + 4u * 6u + d] = -d_final;
  }
}
