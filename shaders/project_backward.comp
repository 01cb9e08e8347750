#version 450
// Projection backward: one invocation per Gaussian gathers its screen-space gradients from its
// intersections' slots (in tile order, no atomics) and propagates them to the map parameters.
// Its contribution to dL/dW and dL/dt of p_cam = W p + t is summed per workgroup in a fixed
// tree and written to pose_partials[workgroup]; the host adds those in double. Reads 0..12,
// writes 13..15. Deterministic.
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"

layout(local_size_x = 256) in;
layout(std430, binding = 6) readonly buffer Conics { float conics[]; };        // [N, 3]
layout(std430, binding = 7) readonly buffer Opacities { float opacities[]; };  // [N]
layout(std430, binding = 8) readonly buffer Radii { int radii[]; };            // [N, 2]
layout(std430, binding = 9) readonly buffer TileCounts { uint tile_counts[]; };  // [N]
layout(std430, binding = 10) readonly buffer FirstInstance { uint first_instance[]; };  // [N]
layout(std430, binding = 11) readonly buffer SortedPosition { uint sorted_position[]; };  // [M]
layout(std430, binding = 12) readonly buffer IsectGrads { float isect_grads[]; };  // [M, kGradSlots]
// dL/d(means 3, log_scales 3, rotations 4, opacity logit 1) per Gaussian.
layout(std430, binding = 13) writeonly buffer DParams { float d_params[]; };  // [N, 11]
layout(std430, binding = 14) writeonly buffer DSh { float d_sh[]; };          // [N, K, 3]
layout(std430, binding = 15) writeonly buffer PosePartials { float pose_partials[]; };  // [groups, 12]

shared float reduction[kPosePartials][kGroupSize];

void main() {
  uint i = gl_GlobalInvocationID.x;
  uint tid = gl_LocalInvocationID.x;
  mat3 v_w = mat3(0);
  vec3 v_t = vec3(0);
  if (i < frame.count) {
    // Screen gradients of this Gaussian: the sum over its intersections.
    float sg[kGradSlots];
    for (uint k = 0u; k < kGradSlots; ++k) sg[k] = 0;
    uint first = first_instance[i];
    for (uint n = 0u; n < tile_counts[i]; ++n) {
      uint s = sorted_position[first + n];
      for (uint k = 0u; k < kGradSlots; ++k) sg[k] += isect_grads[s * kGradSlots + k];
    }
    mat3 w = camera_rotation();
    vec3 t = camera_translation();
    vec3 p_world = load_mean(i);
    vec3 p = transform_point(w, t, p_world);
    vec3 v_p_world = vec3(0);
    vec3 v_p = vec3(0);

    // Colour: SH coefficients and the view direction.
    vec3 dir = p_world - camera_position();
    float dir_len = length(dir);
    int used_degree = dir_len > 0 ? frame.sh_degree : 0;
    vec3 unit = dir_len > 0 ? dir / dir_len : dir;
    float basis[16];
    sh_basis(used_degree, unit, basis);
    int used = sh_coeff_count(used_degree);
    float w_basis[16];
    for (int k = 0; k < 16; ++k) w_basis[k] = 0;
    uint stride = frame.sh_stride * 3u;
    for (uint k = 0u; k < stride; ++k) d_sh[i * stride + k] = 0;
    vec3 v_color = vec3(sg[kSlotRed], sg[kSlotGreen], sg[kSlotBlue]);
    for (int c = 0; c < 3; ++c) {
      float raw = 0.5;
      for (int k = 0; k < used; ++k) raw += basis[k] * load_sh(i, k, c);
      if (raw < 0) continue;  // clamped at zero: no gradient
      for (int k = 0; k < used; ++k) {
        d_sh[(i * frame.sh_stride + uint(k)) * 3u + uint(c)] = basis[k] * v_color[c];
        w_basis[k] += load_sh(i, k, c) * v_color[c];
      }
    }
    if (used_degree > 0 && frame.sh_direction_gradient != 0u) {
      vec3 v_dir = normalize_vjp(dir, sh_basis_vjp(used_degree, unit, w_basis));
      v_p_world += v_dir;
      // dir = mean - c, c = -W^T t: dL/dt += W v_dir, dL/dW += t v_dir^T.
      v_t += w * v_dir;
      v_w += outerProduct(t, v_dir);
    }

    float opacity = opacities[i];
    d_params[i * 11u + 10u] = sg[kSlotOpacity] * opacity * (1 - opacity);
    vec4 v_q = vec4(0);
    vec3 v_log_scale = vec3(0);
    bool visible = radii[2 * i] > 0 || radii[2 * i + 1] > 0;
    if (visible) {
      v_p.z += sg[kSlotDepth];
      vec4 q = load_rotation(i);
      vec4 unit_q = q / length(q);
      vec3 log_scale = load_log_scale(i);
      mat3 sigma = covariance_3d(unit_q, log_scale);
      mat3 sigma_cam = w * sigma * transpose(w);
      vec3 conic = vec3(conics[3 * i], conics[3 * i + 1], conics[3 * i + 2]);
      mat2 v_cov2d = invert_sym2_vjp(conic, vec3(sg[kSlotConicA], sg[kSlotConicB], sg[kSlotConicC]));
      mat3 v_sigma_cam = mat3(0);
      projection_vjp(p, sigma_cam, vec2(sg[kSlotMeanX], sg[kSlotMeanY]), v_cov2d, v_p, v_sigma_cam);
      // Sigma_cam = W Sigma W^T.
      mat3 v_sigma = transpose(w) * v_sigma_cam * w;
      v_w += (v_sigma_cam + transpose(v_sigma_cam)) * w * sigma;
      vec4 v_unit_q = vec4(0);
      covariance_3d_vjp(unit_q, log_scale, v_sigma, v_unit_q, v_log_scale);
      v_q = normalize_vjp(q, v_unit_q);
    }
    // p_cam = W p_world + t.
    v_p_world += transpose(w) * v_p;
    v_w += outerProduct(v_p, p_world);
    v_t += v_p;
    for (uint k = 0u; k < 3u; ++k) {
      d_params[i * 11u + k] = v_p_world[k];
      d_params[i * 11u + 3u + k] = v_log_scale[k];
    }
    for (uint k = 0u; k < 4u; ++k) d_params[i * 11u + 6u + k] = v_q[k];
  }
  // Workgroup sum of dL/dW (row-major) and dL/dt, in a fixed tree.
  for (uint r = 0u; r < 3u; ++r) {
    for (uint c = 0u; c < 3u; ++c) reduction[r * 3u + c][tid] = v_w[c][r];
    reduction[9u + r][tid] = v_t[r];
  }
  barrier();
  for (uint half_size = kGroupSize / 2u; half_size > 0u; half_size >>= 1) {
    if (tid < half_size) {
      for (uint k = 0u; k < kPosePartials; ++k) reduction[k][tid] += reduction[k][tid + half_size];
    }
    barrier();
  }
  if (tid < kPosePartials) pose_partials[gl_WorkGroupID.x * kPosePartials + tid] = reduction[tid][0];
}
