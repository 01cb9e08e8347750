// Per-Gaussian maths of the splatting model and their vector-Jacobian products: the GLSL twin
// of splat/src/cpu/math.h, line for line (GLSL and GLM share column-major m[column][row]).
#ifndef GSLAM_SPLAT_MATH_GLSL
#define GSLAM_SPLAT_MATH_GLSL

// p_cam = W p + t evaluated in double and rounded once, as transform_point in the CPU
// reference: both backends get bit-identical camera depths (float evaluation differs by an ulp
// with the order of operations and fused multiply-adds), so near-equal depths sort alike.
vec3 transform_point(mat3 w, vec3 t, vec3 p) { return vec3(dmat3(w) * dvec3(p) + dvec3(t)); }

float frobenius(mat3 a, mat3 b) { return dot(a[0], b[0]) + dot(a[1], b[1]) + dot(a[2], b[2]); }

// Rotation matrix of a unit quaternion q = (w, x, y, z).
mat3 quat_to_rotmat(vec4 q) {
  float w = q[0], x = q[1], y = q[2], z = q[3];
  return transpose(mat3(1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
                        2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                        2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)));
}

// VJP of quat_to_rotmat: dL/dq (unit quaternion) from dL/dR.
vec4 quat_to_rotmat_vjp(vec4 q, mat3 v_r) {
  float w = q[0], x = q[1], y = q[2], z = q[3];
  mat3 d_w = transpose(mat3(0, -2 * z, 2 * y, 2 * z, 0, -2 * x, -2 * y, 2 * x, 0));
  mat3 d_x = transpose(mat3(0, 2 * y, 2 * z, 2 * y, -4 * x, -2 * w, 2 * z, 2 * w, -4 * x));
  mat3 d_y = transpose(mat3(-4 * y, 2 * x, 2 * w, 2 * x, 0, 2 * z, -2 * w, 2 * z, -4 * y));
  mat3 d_z = transpose(mat3(-4 * z, -2 * w, 2 * x, 2 * w, -4 * z, 2 * y, 2 * x, 2 * y, 0));
  return vec4(frobenius(v_r, d_w), frobenius(v_r, d_x), frobenius(v_r, d_y), frobenius(v_r, d_z));
}

// VJP of v / |v|.
vec3 normalize_vjp(vec3 v, vec3 v_unit) {
  float inv_norm = 1 / length(v);
  vec3 unit = v * inv_norm;
  return (v_unit - unit * dot(unit, v_unit)) * inv_norm;
}
vec4 normalize_vjp(vec4 v, vec4 v_unit) {
  float inv_norm = 1 / length(v);
  vec4 unit = v * inv_norm;
  return (v_unit - unit * dot(unit, v_unit)) * inv_norm;
}

// Sigma = R S S^T R^T, S = diag(exp(log_scale)).
mat3 covariance_3d(vec4 unit_quat, vec3 log_scale) {
  mat3 r = quat_to_rotmat(unit_quat);
  vec3 s = exp(log_scale);
  mat3 m = r * mat3(s[0], 0, 0, 0, s[1], 0, 0, 0, s[2]);
  return m * transpose(m);
}

// VJP of covariance_3d from dL/dSigma (full symmetric): accumulates into the outputs.
void covariance_3d_vjp(vec4 unit_quat, vec3 log_scale, mat3 v_sigma, inout vec4 v_unit_quat,
                       inout vec3 v_log_scale) {
  mat3 r = quat_to_rotmat(unit_quat);
  vec3 s = exp(log_scale);
  mat3 m = r * mat3(s[0], 0, 0, 0, s[1], 0, 0, 0, s[2]);
  mat3 v_m = (v_sigma + transpose(v_sigma)) * m;  // Sigma = M M^T
  mat3 v_r;
  for (int j = 0; j < 3; ++j) {  // M = R S: column j of M is s_j times column j of R
    v_r[j] = v_m[j] * s[j];
    v_log_scale[j] += dot(r[j], v_m[j]) * s[j];
  }
  v_unit_quat += quat_to_rotmat_vjp(unit_quat, v_r);
}

// Clamped x/z, y/z for the EWA Jacobian, and whether each was left unclamped.
void clamped_ratios(vec3 p, out float u, out float v, out bool u_free, out bool v_free) {
  float raw_u = p.x / p.z, raw_v = p.y / p.z;
  u = min(frame.lim_x_pos, max(-frame.lim_x_neg, raw_u));
  v = min(frame.lim_y_pos, max(-frame.lim_y_neg, raw_v));
  u_free = u == raw_u;
  v_free = v == raw_v;
}

// Jacobian of the perspective projection at the clamped point (2 rows, 3 columns).
mat3x2 projection_jacobian(vec3 p) {
  float u, v;
  bool u_free, v_free;
  clamped_ratios(p, u, v, u_free, v_free);
  float rz = 1 / p.z;
  return mat3x2(frame.fx * rz, 0, 0, frame.fy * rz, -frame.fx * u * rz, -frame.fy * v * rz);
}

vec2 project_mean(vec3 p) { return vec2(frame.fx * p.x / p.z + frame.cx, frame.fy * p.y / p.z + frame.cy); }

mat2 project_cov(vec3 p, mat3 sigma_cam) {
  mat3x2 j = projection_jacobian(p);
  return j * sigma_cam * transpose(j);
}

// VJP of (project_mean, project_cov): accumulates dL/dp and dL/dSigma_cam.
void projection_vjp(vec3 p, mat3 sigma_cam, vec2 v_mean2d, mat2 v_cov2d, inout vec3 v_p,
                    inout mat3 v_sigma_cam) {
  float u, v;
  bool u_free, v_free;
  clamped_ratios(p, u, v, u_free, v_free);
  float fx = frame.fx, fy = frame.fy;
  float rz = 1 / p.z, rz2 = rz * rz;
  mat3x2 j = projection_jacobian(p);
  v_p.x += fx * rz * v_mean2d.x;
  v_p.y += fy * rz * v_mean2d.y;
  v_p.z -= (fx * p.x * v_mean2d.x + fy * p.y * v_mean2d.y) * rz2;
  v_sigma_cam += transpose(j) * v_cov2d * j;
  mat3x2 v_j = (v_cov2d + transpose(v_cov2d)) * j * sigma_cam;
  float v_j00 = v_j[0][0], v_j11 = v_j[1][1], v_j02 = v_j[2][0], v_j12 = v_j[2][1];
  v_p.z -= (fx * v_j00 + fy * v_j11) * rz2;
  if (u_free) {
    v_p.x -= fx * rz2 * v_j02;
    v_p.z += 2 * fx * u * rz2 * v_j02;
  } else {
    v_p.z += fx * u * rz2 * v_j02;
  }
  if (v_free) {
    v_p.y -= fy * rz2 * v_j12;
    v_p.z += 2 * fy * v * rz2 * v_j12;
  } else {
    v_p.z += fy * v * rz2 * v_j12;
  }
}

bool invert_sym2(mat2 m, out vec3 conic) {
  float det = m[0][0] * m[1][1] - m[1][0] * m[1][0];
  conic = vec3(0);
  if (!(det > 0)) return false;
  float inv = 1 / det;
  conic = vec3(m[1][1] * inv, -m[1][0] * inv, m[0][0] * inv);
  return true;
}

mat2 invert_sym2_vjp(vec3 conic, vec3 v_conic) {
  mat2 q = mat2(conic[0], conic[1], conic[1], conic[2]);
  mat2 g = mat2(v_conic[0], v_conic[1] / 2, v_conic[1] / 2, v_conic[2]);
  return -(q * g * q);
}

// Real SH basis (INRIA/gsplat order) of a unit direction up to `degree`.
const float kShC0 = 0.28209479177387814;
const float kShC1 = 0.4886025119029199;
const float kShC2[5] = float[5](1.0925484305920792, -1.0925484305920792, 0.31539156525252005,
                                -1.0925484305920792, 0.5462742152960396);
const float kShC3[7] = float[7](-0.5900435899266435, 2.890611442640554, -0.4570457994644658,
                                0.3731763325901154, -0.4570457994644658, 1.445305721320277,
                                -0.5900435899266435);

void sh_basis(int degree, vec3 d, out float b[16]) {
  for (int k = 0; k < 16; ++k) b[k] = 0;
  float x = d.x, y = d.y, z = d.z;
  b[0] = kShC0;
  if (degree < 1) return;
  b[1] = -kShC1 * y;
  b[2] = kShC1 * z;
  b[3] = -kShC1 * x;
  if (degree < 2) return;
  float xx = x * x, yy = y * y, zz = z * z;
  b[4] = kShC2[0] * x * y;
  b[5] = kShC2[1] * y * z;
  b[6] = kShC2[2] * (2 * zz - xx - yy);
  b[7] = kShC2[3] * x * z;
  b[8] = kShC2[4] * (xx - yy);
  if (degree < 3) return;
  b[9] = kShC3[0] * y * (3 * xx - yy);
  b[10] = kShC3[1] * x * y * z;
  b[11] = kShC3[2] * y * (4 * zz - xx - yy);
  b[12] = kShC3[3] * z * (2 * zz - 3 * xx - 3 * yy);
  b[13] = kShC3[4] * x * (4 * zz - xx - yy);
  b[14] = kShC3[5] * z * (xx - yy);
  b[15] = kShC3[6] * x * (xx - 3 * yy);
}

// dL/d(direction) of sum_k b_k(d) w_k.
vec3 sh_basis_vjp(int degree, vec3 d, float w[16]) {
  float x = d.x, y = d.y, z = d.z;
  vec3 g = vec3(0);
  if (degree < 1) return g;
  g.y += -kShC1 * w[1];
  g.z += kShC1 * w[2];
  g.x += -kShC1 * w[3];
  if (degree < 2) return g;
  float xx = x * x, yy = y * y, zz = z * z;
  g += vec3(y, x, 0) * (kShC2[0] * w[4]);
  g += vec3(0, z, y) * (kShC2[1] * w[5]);
  g += vec3(-2 * x, -2 * y, 4 * z) * (kShC2[2] * w[6]);
  g += vec3(z, 0, x) * (kShC2[3] * w[7]);
  g += vec3(2 * x, -2 * y, 0) * (kShC2[4] * w[8]);
  if (degree < 3) return g;
  g += vec3(6 * x * y, 3 * xx - 3 * yy, 0) * (kShC3[0] * w[9]);
  g += vec3(y * z, x * z, x * y) * (kShC3[1] * w[10]);
  g += vec3(-2 * x * y, 4 * zz - xx - 3 * yy, 8 * y * z) * (kShC3[2] * w[11]);
  g += vec3(-6 * x * z, -6 * y * z, 6 * zz - 3 * xx - 3 * yy) * (kShC3[3] * w[12]);
  g += vec3(4 * zz - 3 * xx - yy, -2 * x * y, 8 * x * z) * (kShC3[4] * w[13]);
  g += vec3(2 * x * z, -2 * y * z, xx - yy) * (kShC3[5] * w[14]);
  g += vec3(3 * xx - 3 * yy, -6 * x * y, 0) * (kShC3[6] * w[15]);
  return g;
}

float sigmoid(float x) { return 1 / (1 + exp(-x)); }

#endif  // GSLAM_SPLAT_MATH_GLSL
