// Per-Gaussian maths of the splatting model and their vector-Jacobian products (VJPs), written
// with GLM so it reads like the GLSL. Templated on scalar: float for rendering, double for
// gradient checks. Matrices are GLM's column-major: m[column][row].
#pragma once
#include <cmath>

#include <glm/glm.hpp>

namespace splat::cpu {

template <typename T>
using Vec2 = glm::vec<2, T>;
template <typename T>
using Vec3 = glm::vec<3, T>;
template <typename T>
using Vec4 = glm::vec<4, T>;
template <typename T>
using Mat2 = glm::mat<2, 2, T>;
template <typename T>
using Mat3 = glm::mat<3, 3, T>;
template <typename T>
using Mat2x3 = glm::mat<3, 2, T>;  // 2 rows, 3 columns (GLM names columns first)

// Frobenius inner product <A, B> = sum_ij A_ij B_ij.
template <typename M>
auto frobenius(const M& a, const M& b) {
  typename M::value_type sum = 0;
  for (int c = 0; c < M::length(); ++c) sum += glm::dot(a[c], b[c]);
  return sum;
}

// p_cam = W p + t evaluated in double and rounded once, as transform_point in the shaders: both
// backends get bit-identical camera depths (float evaluation differs by an ulp with the order of
// operations and fused multiply-adds), so near-equal depths sort alike.
template <typename T>
Vec3<T> transform_point(const Mat3<T>& w, const Vec3<T>& t, const Vec3<T>& p) {
  return Vec3<T>(Mat3<double>(w) * Vec3<double>(p) + Vec3<double>(t));
}

// Rotation matrix of a unit quaternion q = (w, x, y, z).
template <typename T>
Mat3<T> quat_to_rotmat(const Vec4<T>& q) {
  const T w = q[0], x = q[1], y = q[2], z = q[3];
  // Written row by row, then transposed into GLM's column-major storage.
  return glm::transpose(Mat3<T>(1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
                                2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                                2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)));
}

// VJP of quat_to_rotmat: dL/dq (unit quaternion) from dL/dR.
template <typename T>
Vec4<T> quat_to_rotmat_vjp(const Vec4<T>& q, const Mat3<T>& v_r) {
  const T w = q[0], x = q[1], y = q[2], z = q[3];
  auto rows = [](T a, T b, T c, T d, T e, T f, T g, T h, T i) {
    return glm::transpose(Mat3<T>(a, b, c, d, e, f, g, h, i));
  };
  const Mat3<T> d_w = rows(0, -2 * z, 2 * y, 2 * z, 0, -2 * x, -2 * y, 2 * x, 0);
  const Mat3<T> d_x = rows(0, 2 * y, 2 * z, 2 * y, -4 * x, -2 * w, 2 * z, 2 * w, -4 * x);
  const Mat3<T> d_y = rows(-4 * y, 2 * x, 2 * w, 2 * x, 0, 2 * z, -2 * w, 2 * z, -4 * y);
  const Mat3<T> d_z = rows(-4 * z, -2 * w, 2 * x, 2 * w, -4 * z, 2 * y, 2 * x, 2 * y, 0);
  return {frobenius(v_r, d_w), frobenius(v_r, d_x), frobenius(v_r, d_y), frobenius(v_r, d_z)};
}

// VJP of v / |v| for any vector length: removes the radial part and scales by 1/|v|.
template <typename V>
V normalize_vjp(const V& v, const V& v_unit) {
  const auto inv_norm = 1 / glm::length(v);
  const V unit = v * inv_norm;
  return (v_unit - unit * glm::dot(unit, v_unit)) * inv_norm;
}

// 3D covariance Sigma = R S S^T R^T, S = diag(exp(log_scale)), R from the unit quaternion.
template <typename T>
Mat3<T> covariance_3d(const Vec4<T>& unit_quat, const Vec3<T>& log_scale) {
  const Mat3<T> r = quat_to_rotmat(unit_quat);
  const Vec3<T> s = glm::exp(log_scale);
  const Mat3<T> m = r * Mat3<T>(s[0], 0, 0, 0, s[1], 0, 0, 0, s[2]);
  return m * glm::transpose(m);
}

// VJP of covariance_3d: accumulates dL/d(unit quaternion) and dL/d(log scale) from dL/dSigma
// (dL/dSigma given as a full symmetric matrix).
template <typename T>
void covariance_3d_vjp(const Vec4<T>& unit_quat, const Vec3<T>& log_scale, const Mat3<T>& v_sigma,
                       Vec4<T>& v_unit_quat, Vec3<T>& v_log_scale) {
  const Mat3<T> r = quat_to_rotmat(unit_quat);
  const Vec3<T> s = glm::exp(log_scale);
  const Mat3<T> m = r * Mat3<T>(s[0], 0, 0, 0, s[1], 0, 0, 0, s[2]);
  // Sigma = M M^T: dL/dM = (V + V^T) M.
  const Mat3<T> v_m = (v_sigma + glm::transpose(v_sigma)) * m;
  // M = R S: column j of M is s_j times column j of R.
  Mat3<T> v_r;
  for (int j = 0; j < 3; ++j) {
    v_r[j] = v_m[j] * s[j];
    v_log_scale[j] += glm::dot(r[j], v_m[j]) * s[j];  // d s_j / d log s_j = s_j
  }
  v_unit_quat += quat_to_rotmat_vjp(unit_quat, v_r);
}

// Screen-space footprint of a camera-space point and covariance (EWA splatting, gsplat 1.5.3):
// mean2d = (fx x/z + cx, fy y/z + cy), cov2d = J Sigma_cam J^T with J the Jacobian of the
// projection evaluated at the point clamped to 1.3x the field of view.
template <typename T>
struct PerspectiveProjection {
  T fx, fy, cx, cy;
  T lim_x_neg, lim_x_pos, lim_y_neg, lim_y_pos;  // bounds on x/z and y/z for the Jacobian

  PerspectiveProjection(T fx_, T fy_, T cx_, T cy_, int width, int height, T margin)
      : fx(fx_), fy(fy_), cx(cx_), cy(cy_) {
    const T tan_fovx = T(0.5) * T(width) / fx, tan_fovy = T(0.5) * T(height) / fy;
    lim_x_pos = (T(width) - cx) / fx + margin * tan_fovx;
    lim_x_neg = cx / fx + margin * tan_fovx;
    lim_y_pos = (T(height) - cy) / fy + margin * tan_fovy;
    lim_y_neg = cy / fy + margin * tan_fovy;
  }

  // Clamped x/z, y/z and whether each was left unclamped (the clamp's derivative).
  void clamped_ratios(const Vec3<T>& p, T& u, T& v, bool& u_free, bool& v_free) const {
    const T raw_u = p.x / p.z, raw_v = p.y / p.z;
    u = std::min(lim_x_pos, std::max(-lim_x_neg, raw_u));
    v = std::min(lim_y_pos, std::max(-lim_y_neg, raw_v));
    u_free = u == raw_u;
    v_free = v == raw_v;
  }

  Mat2x3<T> jacobian(const Vec3<T>& p) const {
    T u, v;
    bool u_free, v_free;
    clamped_ratios(p, u, v, u_free, v_free);
    const T rz = 1 / p.z;
    // Row-major [[fx/z, 0, -fx u/z], [0, fy/z, -fy v/z]]; GLM stores columns.
    return Mat2x3<T>(fx * rz, 0, 0, fy * rz, -fx * u * rz, -fy * v * rz);
  }

  Vec2<T> mean2d(const Vec3<T>& p) const {
    return {fx * p.x / p.z + cx, fy * p.y / p.z + cy};
  }

  Mat2<T> cov2d(const Vec3<T>& p, const Mat3<T>& sigma_cam) const {
    const Mat2x3<T> j = jacobian(p);
    return j * sigma_cam * glm::transpose(j);
  }

  // VJP: accumulates dL/dp and dL/dSigma_cam from dL/dmean2d and dL/dcov2d (full symmetric).
  void vjp(const Vec3<T>& p, const Mat3<T>& sigma_cam, const Vec2<T>& v_mean2d,
           const Mat2<T>& v_cov2d, Vec3<T>& v_p, Mat3<T>& v_sigma_cam) const {
    T u, v;
    bool u_free, v_free;
    clamped_ratios(p, u, v, u_free, v_free);
    const T rz = 1 / p.z, rz2 = rz * rz;
    const Mat2x3<T> j = jacobian(p);
    // mean2d
    v_p.x += fx * rz * v_mean2d.x;
    v_p.y += fy * rz * v_mean2d.y;
    v_p.z -= (fx * p.x * v_mean2d.x + fy * p.y * v_mean2d.y) * rz2;
    // cov2d = J S J^T: dL/dS = J^T V J, dL/dJ = (V + V^T) J S.
    v_sigma_cam += glm::transpose(j) * v_cov2d * j;
    const Mat2x3<T> v_j = (v_cov2d + glm::transpose(v_cov2d)) * j * sigma_cam;
    // J00 = fx/z, J11 = fy/z, J02 = -fx c(x/z)/z, J12 = -fy c(y/z)/z; c = clamp, c' in {0, 1}.
    const T v_j00 = v_j[0][0], v_j11 = v_j[1][1], v_j02 = v_j[2][0], v_j12 = v_j[2][1];
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
};

// Inverse of a symmetric 2x2 matrix [[a, b], [b, c]] given as (a, b, c); false if singular.
template <typename T>
bool invert_sym2(const Mat2<T>& m, Vec3<T>& conic) {
  const T det = m[0][0] * m[1][1] - m[1][0] * m[1][0];
  if (!(det > 0)) return false;
  const T inv = 1 / det;
  conic = {m[1][1] * inv, -m[1][0] * inv, m[0][0] * inv};
  return true;
}

// VJP of the inverse: dL/dM = -Q G Q with Q the conic and G the gradient as a full symmetric
// matrix (the off-diagonal parameter b appears twice, so each entry gets half of dL/db).
template <typename T>
Mat2<T> invert_sym2_vjp(const Vec3<T>& conic, const Vec3<T>& v_conic) {
  const Mat2<T> q(conic[0], conic[1], conic[1], conic[2]);
  const Mat2<T> g(v_conic[0], v_conic[1] / 2, v_conic[1] / 2, v_conic[2]);
  return -(q * g * q);
}

// Normalization constants of the real SH basis, degrees 0..3.
template <typename T>
struct ShConstants {
  static constexpr T c0 = T(0.28209479177387814);
  static constexpr T c1 = T(0.4886025119029199);
  static constexpr T c2[5] = {T(1.0925484305920792), T(-1.0925484305920792), T(0.31539156525252005),
                              T(-1.0925484305920792), T(0.5462742152960396)};
  static constexpr T c3[7] = {T(-0.5900435899266435), T(2.890611442640554), T(-0.4570457994644658),
                              T(0.3731763325901154),  T(-0.4570457994644658), T(1.445305721320277),
                              T(-0.5900435899266435)};
};

// Real spherical-harmonics basis (with the Condon-Shortley phase, INRIA/gsplat order) of a unit
// direction, up to `degree`; writes (degree+1)^2 values.
template <typename T>
void sh_basis(int degree, const Vec3<T>& d, T* b) {
  using C = ShConstants<T>;
  constexpr T kC0 = C::c0, kC1 = C::c1;
  constexpr const T* kC2 = C::c2;
  constexpr const T* kC3 = C::c3;
  const T x = d.x, y = d.y, z = d.z;
  b[0] = kC0;
  if (degree < 1) return;
  b[1] = -kC1 * y;
  b[2] = kC1 * z;
  b[3] = -kC1 * x;
  if (degree < 2) return;
  const T xx = x * x, yy = y * y, zz = z * z;
  b[4] = kC2[0] * x * y;
  b[5] = kC2[1] * y * z;
  b[6] = kC2[2] * (2 * zz - xx - yy);
  b[7] = kC2[3] * x * z;
  b[8] = kC2[4] * (xx - yy);
  if (degree < 3) return;
  b[9] = kC3[0] * y * (3 * xx - yy);
  b[10] = kC3[1] * x * y * z;
  b[11] = kC3[2] * y * (4 * zz - xx - yy);
  b[12] = kC3[3] * z * (2 * zz - 3 * xx - 3 * yy);
  b[13] = kC3[4] * x * (4 * zz - xx - yy);
  b[14] = kC3[5] * z * (xx - yy);
  b[15] = kC3[6] * x * (xx - 3 * yy);
}

// dL/d(direction) of sum_k b_k(d) w_k, where w_k = sum_c sh_kc dL/dcolour_c (given as `w`).
template <typename T>
Vec3<T> sh_basis_vjp(int degree, const Vec3<T>& d, const T* w) {
  using C = ShConstants<T>;
  constexpr T kC1 = C::c1;
  constexpr const T* kC2 = C::c2;
  constexpr const T* kC3 = C::c3;
  const T x = d.x, y = d.y, z = d.z;
  Vec3<T> g(0);
  if (degree < 1) return g;
  g.y += -kC1 * w[1];
  g.z += kC1 * w[2];
  g.x += -kC1 * w[3];
  if (degree < 2) return g;
  const T xx = x * x, yy = y * y, zz = z * z;
  g += Vec3<T>(y, x, 0) * (kC2[0] * w[4]);
  g += Vec3<T>(0, z, y) * (kC2[1] * w[5]);
  g += Vec3<T>(-2 * x, -2 * y, 4 * z) * (kC2[2] * w[6]);
  g += Vec3<T>(z, 0, x) * (kC2[3] * w[7]);
  g += Vec3<T>(2 * x, -2 * y, 0) * (kC2[4] * w[8]);
  if (degree < 3) return g;
  g += Vec3<T>(6 * x * y, 3 * xx - 3 * yy, 0) * (kC3[0] * w[9]);
  g += Vec3<T>(y * z, x * z, x * y) * (kC3[1] * w[10]);
  g += Vec3<T>(-2 * x * y, 4 * zz - xx - 3 * yy, 8 * y * z) * (kC3[2] * w[11]);
  g += Vec3<T>(-6 * x * z, -6 * y * z, 6 * zz - 3 * xx - 3 * yy) * (kC3[3] * w[12]);
  g += Vec3<T>(4 * zz - 3 * xx - yy, -2 * x * y, 8 * x * z) * (kC3[4] * w[13]);
  g += Vec3<T>(2 * x * z, -2 * y * z, xx - yy) * (kC3[5] * w[14]);
  g += Vec3<T>(3 * xx - 3 * yy, -6 * x * y, 0) * (kC3[6] * w[15]);
  return g;
}

template <typename T>
T sigmoid(T x) {
  return 1 / (1 + std::exp(-x));
}

}  // namespace splat::cpu
