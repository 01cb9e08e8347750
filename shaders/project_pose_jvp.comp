#version 450
// Forward-mode pose derivatives of the screen quantities: one invocation per Gaussian writes
// d(mean x, y, conic a, b, c, depth, colour r, g, b)/d(pose) for the 6 directions of the left
// perturbation, [N, kScreenValues, 6]; zero for culled Gaussians. Reads 0..7, writes 8.
#extension GL_GOOGLE_include_directive : require
#include "frame.glsl"

layout(local_size_x = 256) in;
layout(std430, binding = 6) readonly buffer Conics { float conics[]; };  // [N, 3]
layout(std430, binding = 7) readonly buffer Radii { int radii[]; };      // [N, 2]
layout(std430, binding = 8) writeonly buffer ScreenJvp { float jvp[]; }; // [N, 9, 6]

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= frame.count) return;
  uint out_base = i * kScreenValues * 6u;
  if (radii[2 * i] <= 0 && radii[2 * i + 1] <= 0) {
    for (uint k = 0u; k < kScreenValues * 6u; ++k) jvp[out_base + k] = 0;
    return;
  }
  mat3 w = camera_rotation();
  vec3 p_world = load_mean(i);
  vec3 p = transform_point(w, camera_translation(), p_world);
  vec4 q = load_rotation(i);
  mat3 sigma = covariance_3d(q / length(q), load_log_scale(i));
  mat3 sigma_cam = w * sigma * transpose(w);
  float u, v;
  bool u_free, v_free;
  clamped_ratios(p, u, v, u_free, v_free);
  mat3x2 j = projection_jacobian(p);
  vec3 conic = vec3(conics[3 * i], conics[3 * i + 1], conics[3 * i + 2]);
  mat2 qm = mat2(conic[0], conic[1], conic[1], conic[2]);
  float rz = 1 / p.z, rz2 = rz * rz;
  float fx = frame.fx, fy = frame.fy;

  // Colour: only the translation moves the camera centre (d centre = -W^T dv).
  vec3 dir = p_world - camera_position();
  float dir_len = length(dir);
  int used_degree = dir_len > 0 && frame.sh_direction_gradient != 0u ? frame.sh_degree : 0;
  vec3 d_color_d_dir[3] = vec3[3](vec3(0), vec3(0), vec3(0));
  if (used_degree > 0) {
    vec3 unit = dir / dir_len;
    float basis[16];
    sh_basis(used_degree, unit, basis);
    for (int c = 0; c < 3; ++c) {
      float raw = 0.5;
      float coeffs[16];
      for (int k = 0; k < 16; ++k) coeffs[k] = 0;
      for (int k = 0; k < sh_coeff_count(used_degree); ++k) {
        coeffs[k] = load_sh(i, k, c);
        raw += basis[k] * coeffs[k];
      }
      if (raw >= 0) d_color_d_dir[c] = normalize_vjp(dir, sh_basis_vjp(used_degree, unit, coeffs));
    }
  }

  for (uint k = 0u; k < 6u; ++k) {
    // Tangent of the perturbation: dp = dv + w x p, dSigma_cam = [w]x S - S [w]x.
    vec3 dv = vec3(0), dw = vec3(0);
    if (k < 3u) dv[k] = 1; else dw[k - 3u] = 1;
    vec3 dp = dv + cross(dw, p);
    mat3 wx = mat3(0, dw.z, -dw.y, -dw.z, 0, dw.x, dw.y, -dw.x, 0);
    mat3 d_sigma_cam = wx * sigma_cam - sigma_cam * wx;
    float d_mx = fx * (dp.x * rz - p.x * dp.z * rz2);
    float d_my = fy * (dp.y * rz - p.y * dp.z * rz2);
    float du = u_free ? dp.x * rz - p.x * dp.z * rz2 : 0.0;
    float dvv = v_free ? dp.y * rz - p.y * dp.z * rz2 : 0.0;
    mat3x2 dj = mat3x2(-fx * dp.z * rz2, 0, 0, -fy * dp.z * rz2, -fx * (du * rz - u * dp.z * rz2),
                       -fy * (dvv * rz - v * dp.z * rz2));
    mat2 d_cov = dj * sigma_cam * transpose(j) + j * d_sigma_cam * transpose(j) +
                 j * sigma_cam * transpose(dj);
    mat2 d_conic = -(qm * d_cov * qm);
    vec3 d_dir = transpose(w) * dv;
    float values[kScreenValues] = float[kScreenValues](
        d_mx, d_my, d_conic[0][0], d_conic[1][0], d_conic[1][1], dp.z,
        dot(d_color_d_dir[0], d_dir), dot(d_color_d_dir[1], d_dir), dot(d_color_d_dir[2], d_dir));
    for (uint s = 0u; s < kScreenValues; ++s) jvp[out_base + s * 6u + k] = values[s];
  }
}
