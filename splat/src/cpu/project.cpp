#include <algorithm>
#include <cmath>
#include <limits>

#include "cpu/math.h"
#include "cpu/stages.h"
#include "render_stats.h"
#include "shader_io.h"

namespace splat::cpu {
namespace {


// Camera extrinsics and intrinsics in the working scalar type.
template <typename T>
struct CameraModel {
  Mat3<T> rotation;      // W: world to camera rotation
  Vec3<T> translation;   // t: p_cam = W p_world + t
  Vec3<T> position;      // camera centre in the world frame, -W^T t
  PerspectiveProjection<T> projection;
  int width, height;

  explicit CameraModel(const Camera& c)
      : projection(T(c.fx), T(c.fy), T(c.cx), T(c.cy), c.width, c.height, T(io::kFovClampMargin)),
        width(c.width),
        height(c.height) {
    const Eigen::Matrix3d r = c.T_cam_world.linear();
    for (int col = 0; col < 3; ++col)
      for (int row = 0; row < 3; ++row) rotation[col][row] = T(r(row, col));
    for (int i = 0; i < 3; ++i) translation[i] = T(c.T_cam_world.translation()[i]);
    position = -(glm::transpose(rotation) * translation);
  }

  // Sigmas a footprint reaches: where opacity * exp(-r^2/2) falls to kAlphaMin, at most
  // kExtentSigmaMax.
  static T extent(T opacity) {
    return std::min(T(io::kExtentSigmaMax), std::sqrt(2 * std::log(opacity / T(io::kAlphaMin))));
  }
  // Whether a box of these half-sizes about m misses the image.
  bool misses_image(const Vec2<T>& m, T half_x, T half_y) const {
    return m.x + half_x <= 0 || m.x - half_x >= T(width) || m.y + half_y <= 0 ||
           m.y - half_y >= T(height);
  }

  // True only where the full test below would cull the Gaussian as off screen, without its
  // covariance: about half a map's Gaussians lie beside the view. cov2d's diagonal is at most
  // |row of J|^2 times Sigma's largest eigenvalue, exp(2 max log scale), plus the dilation, so
  // 1.001 (rounding) extend sqrt(that) + 1 (the ceil) exceeds each radius. The map is finite
  // (validate()). Faint Gaussians, a quaternion whose squared length is subnormal (its unit
  // quaternion is not unit) and footprints over kSigmaMax pixels (where rounding can make cov2d
  // singular: degenerate, not off screen) take the full test, which labels them.
  bool surely_offscreen(const Vec3<T>& p, const Vec4<T>& q, const Vec3<T>& log_scale, T opacity) const {
    constexpr T kSigmaMax = 256;
    const Vec2<T> m = projection.mean2d(p);
    if (m.x >= 0 && m.x <= T(width) && m.y >= 0 && m.y <= T(height)) return false;
    if (!(opacity >= T(io::kAlphaMin)) || !(glm::dot(q, q) >= std::numeric_limits<T>::min())) return false;
    T u, v;
    bool u_free, v_free;
    projection.clamped_ratios(p, u, v, u_free, v_free);
    const T largest = std::exp(2 * std::max(log_scale.x, std::max(log_scale.y, log_scale.z)));
    const T fx_z = projection.fx / p.z, fy_z = projection.fy / p.z;
    const T dilation = T(io::kCov2dDilation);
    const T sigma_x = std::sqrt(fx_z * fx_z * (1 + u * u) * largest + dilation);
    const T sigma_y = std::sqrt(fy_z * fy_z * (1 + v * v) * largest + dilation);
    if (!(sigma_x <= kSigmaMax && sigma_y <= kSigmaMax)) return false;
    const T extend = extent(opacity);
    return misses_image(m, T(1.001) * extend * sigma_x + 1, T(1.001) * extend * sigma_y + 1);
  }
};

template <typename T>
Vec3<T> load3(std::span<const T> a, std::size_t i) {
  return {a[3 * i], a[3 * i + 1], a[3 * i + 2]};
}
template <typename T>
Vec4<T> load4(std::span<const T> a, std::size_t i) {
  return {a[4 * i], a[4 * i + 1], a[4 * i + 2], a[4 * i + 3]};
}

int effective_degree(int map_degree, const RenderSettings& settings) {
  return settings.sh_degree < 0 ? map_degree : std::min(map_degree, settings.sh_degree);
}

}  // namespace

template <typename T>
void project_forward(ForwardResultT<T>& frame, ThreadPool& pool) {
  const GaussiansViewT<T>& g = frame.gaussians;
  const std::size_t n = g.size();
  const CameraModel<T> cam(frame.camera);
  const int degree = effective_degree(g.sh_degree, frame.settings);
  const int stride_k = sh_coeff_count(g.sh_degree);
  frame.means2d.assign(n * 2, 0);
  frame.conics.assign(n * 3, 0);
  frame.depths.assign(n, 0);
  frame.radii.assign(n * 2, 0);
  frame.colors.assign(n * 3, 0);
  frame.opacities.assign(n, 0);
  std::vector<uint32_t> cull(n, io::kCullNone);

  constexpr std::size_t kChunk = 1024;
  pool.parallel_for((n + kChunk - 1) / kChunk, [&](std::size_t chunk) {
    const std::size_t end = std::min(n, (chunk + 1) * kChunk);
    for (std::size_t i = chunk * kChunk; i < end; ++i) {
      const Vec3<T> p_world = load3(g.means, i);
      const Vec3<T> p = transform_point(cam.rotation, cam.translation, p_world);
      const T opacity = sigmoid(g.opacity_logits[i]);
      frame.opacities[i] = opacity;
      frame.depths[i] = p.z;

      // Colour for this view: SH at the unit direction from the camera, +0.5, clamped at 0.
      T basis[16];
      const Vec3<T> dir = p_world - cam.position;
      const T dir_len = glm::length(dir);
      sh_basis(dir_len > 0 ? degree : 0, dir_len > 0 ? dir / dir_len : dir, basis);
      const int used = dir_len > 0 ? sh_coeff_count(degree) : 1;
      for (int c = 0; c < 3; ++c) {
        T sum = 0;
        for (int k = 0; k < used; ++k) sum += basis[k] * g.sh[(i * stride_k + k) * 3 + c];
        frame.colors[i * 3 + c] = std::max(sum + T(0.5), T(0));
      }

      if (p.z < T(frame.camera.near) || p.z > T(frame.camera.far)) {
        cull[i] = io::kCullDepth;
        continue;
      }
      const Vec4<T> q = load4(g.rotations, i);
      const T q_len = glm::length(q);
      if (!(q_len > 0)) {
        cull[i] = io::kCullDegenerate;
        continue;
      }
      if (cam.surely_offscreen(p, q, load3(g.log_scales, i), opacity)) {
        cull[i] = io::kCullOffscreen;
        continue;
      }
      // EWA: Sigma_cam = W Sigma W^T, cov2d = J Sigma_cam J^T + dilation.
      const Mat3<T> sigma = covariance_3d(q / q_len, load3(g.log_scales, i));
      const Mat3<T> sigma_cam = cam.rotation * sigma * glm::transpose(cam.rotation);
      Mat2<T> cov2d = cam.projection.cov2d(p, sigma_cam);
      cov2d[0][0] += T(io::kCov2dDilation);
      cov2d[1][1] += T(io::kCov2dDilation);
      Vec3<T> conic;
      if (!invert_sym2(cov2d, conic)) {
        cull[i] = io::kCullDegenerate;
        continue;
      }
      if (opacity < T(io::kAlphaMin)) {
        cull[i] = io::kCullFaint;
        continue;
      }
      const T extend = CameraModel<T>::extent(opacity);
      const T radius_x = std::ceil(extend * std::sqrt(cov2d[0][0]));
      const T radius_y = std::ceil(extend * std::sqrt(cov2d[1][1]));
      const Vec2<T> mean2d = cam.projection.mean2d(p);
      if ((radius_x <= 0 && radius_y <= 0) || cam.misses_image(mean2d, radius_x, radius_y)) {
        cull[i] = io::kCullOffscreen;
        continue;
      }
      frame.means2d[i * 2] = mean2d.x;
      frame.means2d[i * 2 + 1] = mean2d.y;
      for (int k = 0; k < 3; ++k) frame.conics[i * 3 + k] = conic[k];
      frame.radii[i * 2] = static_cast<int32_t>(radius_x);
      frame.radii[i * 2 + 1] = static_cast<int32_t>(radius_y);
    }
  });

  frame.stats = tally_cull_reasons(cull);
}

template <typename T>
void project_backward(const ForwardResultT<T>& frame, const ScreenGrads<T>& screen,
                      BackwardResultT<T>& out, ThreadPool& pool) {
  const GaussiansViewT<T>& g = frame.gaussians;
  const std::size_t n = g.size();
  const CameraModel<T> cam(frame.camera);
  const int degree = effective_degree(g.sh_degree, frame.settings);
  const int stride_k = sh_coeff_count(g.sh_degree);
  // Fresh, so zero: culled Gaussians and clamped colours are never written below.
  GaussianGradsT<T>& d = out.d_gaussians = GaussianGradsT<T>{};
  d.sh_degree = g.sh_degree;
  d.resize(n);

  // Pose gradient, summed per fixed-size chunk and then in chunk order: the result does not
  // depend on the thread count. dL/dW (3x3) and dL/dt (3) of p_cam = W p + t.
  constexpr std::size_t kChunk = 1024;
  const std::size_t chunks = (n + kChunk - 1) / kChunk;
  std::vector<Mat3<double>> chunk_v_w(chunks, Mat3<double>(0));
  std::vector<Vec3<double>> chunk_v_t(chunks, Vec3<double>(0));

  pool.parallel_for(chunks, [&](std::size_t chunk) {
    const std::size_t begin = chunk * kChunk, end = std::min(n, (chunk + 1) * kChunk);
    Mat3<T> v_w(0);
    Vec3<T> v_t(0);
    for (std::size_t i = begin; i < end; ++i) {
      // Off screen (no tile reached): every screen gradient is zero, and so is every gradient
      // below.
      if (frame.radii[i * 2] <= 0 && frame.radii[i * 2 + 1] <= 0) continue;
      const Vec3<T> p_world = load3(g.means, i);
      const Vec3<T> p = transform_point(cam.rotation, cam.translation, p_world);
      Vec3<T> v_p_world(0);  // dL/d mean (world)
      Vec3<T> v_p(0);        // dL/d p_cam

      // Colour: SH coefficients and the view direction.
      const Vec3<T> dir = p_world - cam.position;
      const T dir_len = glm::length(dir);
      const int used_degree = dir_len > 0 ? degree : 0;
      const Vec3<T> unit = dir_len > 0 ? dir / dir_len : dir;
      T basis[16];
      sh_basis(used_degree, unit, basis);
      const int used = sh_coeff_count(used_degree);
      T w_basis[16] = {};
      for (int c = 0; c < 3; ++c) {
        T raw = T(0.5);
        for (int k = 0; k < used; ++k) raw += basis[k] * g.sh[(i * stride_k + k) * 3 + c];
        if (raw < 0) continue;  // clamped at zero: no gradient
        const T v_c = screen.colors[i * 3 + c];
        for (int k = 0; k < used; ++k) {
          d.sh[(i * stride_k + k) * 3 + c] = basis[k] * v_c;
          w_basis[k] += g.sh[(i * stride_k + k) * 3 + c] * v_c;
        }
      }
      if (used_degree > 0 && frame.settings.sh_direction_gradient) {
        const Vec3<T> v_dir = normalize_vjp(dir, sh_basis_vjp(used_degree, unit, w_basis));
        v_p_world += v_dir;
        // dir = mean - c with camera centre c = -W^T t, so dL/dc = -v_dir and the pose gets
        // dL/dt += W v_dir, dL/dW += t v_dir^T (GLM: outerProduct(a, b) = a b^T).
        v_t += cam.rotation * v_dir;
        v_w += glm::outerProduct(cam.translation, v_dir);
      }

      const T opacity = frame.opacities[i];
      d.opacity_logits[i] = screen.opacities[i] * opacity * (1 - opacity);

      const bool visible = frame.radii[i * 2] > 0 || frame.radii[i * 2 + 1] > 0;
      if (visible) {
        v_p.z += screen.depths[i];
        const Vec4<T> q = load4(g.rotations, i);
        const T q_len = glm::length(q);
        const Vec4<T> unit_q = q / q_len;
        const Vec3<T> log_scale = load3(g.log_scales, i);
        const Mat3<T> sigma = covariance_3d(unit_q, log_scale);
        const Mat3<T> sigma_cam = cam.rotation * sigma * glm::transpose(cam.rotation);
        const Vec3<T> conic(frame.conics[i * 3], frame.conics[i * 3 + 1], frame.conics[i * 3 + 2]);
        const Vec3<T> v_conic(screen.conics[i * 3], screen.conics[i * 3 + 1],
                              screen.conics[i * 3 + 2]);
        const Mat2<T> v_cov2d = invert_sym2_vjp(conic, v_conic);  // dilation adds no gradient
        const Vec2<T> v_mean2d(screen.means2d[i * 2], screen.means2d[i * 2 + 1]);
        Mat3<T> v_sigma_cam(0);
        cam.projection.vjp(p, sigma_cam, v_mean2d, v_cov2d, v_p, v_sigma_cam);
        // Sigma_cam = W Sigma W^T.
        const Mat3<T> v_sigma = glm::transpose(cam.rotation) * v_sigma_cam * cam.rotation;
        v_w += (v_sigma_cam + glm::transpose(v_sigma_cam)) * cam.rotation * sigma;
        Vec4<T> v_unit_q(0);
        Vec3<T> v_log_scale(0);
        covariance_3d_vjp(unit_q, log_scale, v_sigma, v_unit_q, v_log_scale);
        const Vec4<T> v_q = normalize_vjp(q, v_unit_q);
        for (int k = 0; k < 4; ++k) d.rotations[i * 4 + k] = v_q[k];
        for (int k = 0; k < 3; ++k) d.log_scales[i * 3 + k] = v_log_scale[k];
      }
      // p_cam = W p_world + t.
      v_p_world += glm::transpose(cam.rotation) * v_p;
      v_w += glm::outerProduct(v_p, p_world);
      v_t += v_p;
      for (int k = 0; k < 3; ++k) d.means[i * 3 + k] = v_p_world[k];
    }
    chunk_v_w[chunk] = Mat3<double>(v_w);
    chunk_v_t[chunk] = Vec3<double>(v_t);
  });

  Mat3<double> v_w(0);
  Vec3<double> v_t(0);
  for (std::size_t c = 0; c < chunks; ++c) {
    v_w += chunk_v_w[c];
    v_t += chunk_v_t[c];
  }
  Eigen::Matrix3d d_w, w;
  for (int row = 0; row < 3; ++row) {
    for (int col = 0; col < 3; ++col) {
      d_w(row, col) = v_w[col][row];
      w(row, col) = double(cam.rotation[col][row]);
    }
  }
  const Eigen::Vector3d t(double(cam.translation.x), double(cam.translation.y), double(cam.translation.z));
  out.d_loss_d_pose = pose_gradient_from(d_w, Eigen::Vector3d(v_t.x, v_t.y, v_t.z), w, t);
}

template void project_forward(ForwardResultT<float>&, ThreadPool&);
template void project_forward(ForwardResultT<double>&, ThreadPool&);
template void project_backward(const ForwardResultT<float>&, const ScreenGrads<float>&,
                               BackwardResultT<float>&, ThreadPool&);
template void project_backward(const ForwardResultT<double>&, const ScreenGrads<double>&,
                               BackwardResultT<double>&, ThreadPool&);

template <typename T>
std::vector<T> project_pose_jvp(const ForwardResultT<T>& frame, ThreadPool& pool) {
  const GaussiansViewT<T>& g = frame.gaussians;
  const std::size_t n = g.size();
  const CameraModel<T> cam(frame.camera);
  const int degree = effective_degree(g.sh_degree, frame.settings);
  const int stride_k = sh_coeff_count(g.sh_degree);
  std::vector<T> out(n * kScreenValues * 6, T(0));
  constexpr std::size_t kChunk = 1024;
  pool.parallel_for((n + kChunk - 1) / kChunk, [&](std::size_t chunk) {
    for (std::size_t i = chunk * kChunk; i < std::min(n, (chunk + 1) * kChunk); ++i) {
      if (frame.radii[i * 2] <= 0 && frame.radii[i * 2 + 1] <= 0) continue;
      T* jac = &out[i * kScreenValues * 6];
      const Vec3<T> p_world = load3(g.means, i);
      const Vec3<T> p = transform_point(cam.rotation, cam.translation, p_world);
      const Vec4<T> q = load4(g.rotations, i);
      const Mat3<T> sigma = covariance_3d(q / glm::length(q), load3(g.log_scales, i));
      const Mat3<T> sigma_cam = cam.rotation * sigma * glm::transpose(cam.rotation);
      const PerspectiveProjection<T>& proj = cam.projection;
      T u, v;
      bool u_free, v_free;
      proj.clamped_ratios(p, u, v, u_free, v_free);
      const Mat2x3<T> j = proj.jacobian(p);
      const Vec3<T> conic(frame.conics[i * 3], frame.conics[i * 3 + 1], frame.conics[i * 3 + 2]);
      const Mat2<T> qm(conic[0], conic[1], conic[1], conic[2]);
      const T rz = 1 / p.z, rz2 = rz * rz;

      // Colour: only the translation moves the camera centre (d centre = -W^T dv).
      const Vec3<T> dir = p_world - cam.position;
      const T dir_len = glm::length(dir);
      const int used_degree = dir_len > 0 && frame.settings.sh_direction_gradient ? degree : 0;
      Vec3<T> d_color_d_dir[3] = {Vec3<T>(0), Vec3<T>(0), Vec3<T>(0)};  // per channel
      if (used_degree > 0) {
        const Vec3<T> unit = dir / dir_len;
        T basis[16];
        sh_basis(used_degree, unit, basis);
        for (int c = 0; c < 3; ++c) {
          T raw = T(0.5), w[16] = {};
          for (int k = 0; k < sh_coeff_count(used_degree); ++k) {
            w[k] = g.sh[(i * stride_k + k) * 3 + c];
            raw += basis[k] * w[k];
          }
          if (raw >= 0) d_color_d_dir[c] = normalize_vjp(dir, sh_basis_vjp(used_degree, unit, w));
        }
      }

      for (int k = 0; k < 6; ++k) {
        // Tangent of the perturbation: dp = dv + w x p, dSigma_cam = [w]x S - S [w]x.
        Vec3<T> dv(0), dw(0);
        (k < 3 ? dv : dw)[k % 3] = 1;
        const Vec3<T> dp = dv + glm::cross(dw, p);
        const Mat3<T> wx(0, dw.z, -dw.y, -dw.z, 0, dw.x, dw.y, -dw.x, 0);  // columns of [w]x
        const Mat3<T> d_sigma_cam = wx * sigma_cam - sigma_cam * wx;
        // mean2d = (fx x/z + cx, fy y/z + cy)
        const T d_mx = proj.fx * (dp.x * rz - p.x * dp.z * rz2);
        const T d_my = proj.fy * (dp.y * rz - p.y * dp.z * rz2);
        // J = [[fx/z, 0, -fx c(x/z)/z], [0, fy/z, -fy c(y/z)/z]], c the clamp (c' = 0 or 1).
        const T du = u_free ? dp.x * rz - p.x * dp.z * rz2 : T(0);
        const T dvv = v_free ? dp.y * rz - p.y * dp.z * rz2 : T(0);
        const Mat2x3<T> dj(-proj.fx * dp.z * rz2, 0, 0, -proj.fy * dp.z * rz2,
                           -proj.fx * (du * rz - u * dp.z * rz2), -proj.fy * (dvv * rz - v * dp.z * rz2));
        const Mat2<T> d_cov = dj * sigma_cam * glm::transpose(j) + j * d_sigma_cam * glm::transpose(j) +
                              j * sigma_cam * glm::transpose(dj);
        const Mat2<T> d_conic = -(qm * d_cov * qm);
        const Vec3<T> d_dir = glm::transpose(cam.rotation) * dv;
        const T values[kScreenValues] = {d_mx, d_my, d_conic[0][0], d_conic[1][0], d_conic[1][1], dp.z,
                                         glm::dot(d_color_d_dir[0], d_dir), glm::dot(d_color_d_dir[1], d_dir),
                                         glm::dot(d_color_d_dir[2], d_dir)};
        for (int s = 0; s < kScreenValues; ++s) jac[s * 6 + k] = values[s];
      }
    }
  });
  return out;
}

template std::vector<float> project_pose_jvp(const ForwardResultT<float>&, ThreadPool&);
template std::vector<double> project_pose_jvp(const ForwardResultT<double>&, ThreadPool&);

}  // namespace splat::cpu
