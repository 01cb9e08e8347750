#include "tracking/tracker.h"

#include <algorithm>
#include <cmath>

#include "splat/adam.h"
#include "splat/error.h"
#include "splat/field_check.h"
#include "splat/se3.h"

namespace tracking {

void TrackingConfig::validate(const std::string& prefix) const {
  const splat::FieldCheck check(prefix);
  if (pyramid.empty()) check.fail("pyramid", "at least one level", "[]");
  if (iterations.size() != pyramid.size()) {
    check.fail("iterations", "one count per pyramid level (" + std::to_string(pyramid.size()) + ")",
               std::to_string(iterations.size()) + " counts");
  }
  for (int f : pyramid) check.at_least("pyramid", f, 1);
  for (int n : iterations) check.at_least("iterations", n, 0);
  check.at_least("warmup_iterations", warmup_iterations, 0);
  check.positive("warmup_step_translation", warmup_step_translation);
  check.positive("warmup_step_rotation", warmup_step_rotation);
  check.positive("depth_sigma", depth_sigma);
  check.positive("color_sigma", color_sigma);
  check.at_least("color_weight", color_weight, 0.0);
  check.at_least("color_max_factor", color_max_factor, 1);
  check.positive("huber", huber);
  if (!(alpha_threshold >= 0 && alpha_threshold < 1)) check.fail("alpha_threshold", "a number in [0, 1)", alpha_threshold);
  check.positive("outlier_factor", outlier_factor);
  check.at_least("min_step_translation", min_step_translation, 0.0);
  check.at_least("min_step_rotation", min_step_rotation, 0.0);
  check.in_range("min_overlap", min_overlap, 0.0, 1.0);
  check.positive("max_median_residual", max_median_residual);
}

namespace {

using Matrix6d = Eigen::Matrix<double, 6, 6>;

// Robust least squares on one render: residuals, their weights and the normal equations.
struct Linearization {
  std::vector<uint8_t> use;  // the pixels this linearization (and its candidates) is scored on
  double cost = 0;
  double overlap = 0;
  double median_depth_residual = 0;
  Matrix6d h = Matrix6d::Zero();
  splat::Vector6d b = splat::Vector6d::Zero();
};

// Huber: weight 1 inside the threshold, threshold/|r| outside; cost rho(r).
double huber_weight(double r, double k) { return std::abs(r) <= k ? 1.0 : k / std::abs(r); }
double huber_cost(double r, double k) { return std::abs(r) <= k ? 0.5 * r * r : k * (std::abs(r) - 0.5 * k); }

// Pixels used: measured depth, reliable silhouette, depth residual not an outlier.
std::vector<uint8_t> usable_pixels(const splat::ForwardResult& render, const splat::RgbdFrame& frame,
                                   const TrackingConfig& c, double& overlap, double& median) {
  const std::size_t pixels = frame.depth.size();
  std::vector<uint8_t> use(pixels, 0);
  std::vector<float> residuals;
  std::size_t valid = 0;
  for (std::size_t p = 0; p < pixels; ++p) {
    if (frame.depth[p] <= 0) continue;
    ++valid;
    if (render.alpha[p] <= c.alpha_threshold) continue;
    use[p] = 1;
    residuals.push_back(std::abs(render.depth_normalized[p] - frame.depth[p]));
  }
  overlap = valid > 0 ? static_cast<double>(residuals.size()) / static_cast<double>(valid) : 0.0;
  median = 0;
  if (residuals.empty()) return use;
  std::nth_element(residuals.begin(), residuals.begin() + static_cast<long>(residuals.size() / 2), residuals.end());
  median = residuals[residuals.size() / 2];
  const double cutoff = c.outlier_factor * std::max(median, 1e-3);
  for (std::size_t p = 0; p < pixels; ++p) {
    if (use[p] && std::abs(render.depth_normalized[p] - frame.depth[p]) > cutoff) use[p] = 0;
  }
  return use;
}

// Cost (and, with a Jacobian, the normal equations) of a render against the frame over
// `pixels` (chosen at the linearization point when null, then kept for its candidates, so a
// step cannot lower the cost by pushing pixels out of the set).
Linearization linearize(const splat::ForwardResult& render, const std::vector<float>* jacobian,
                        const splat::RgbdFrame& frame, const TrackingConfig& c,
                        const std::vector<uint8_t>* pixels = nullptr) {
  Linearization lin;
  lin.use = pixels ? *pixels : usable_pixels(render, frame, c, lin.overlap, lin.median_depth_residual);
  const std::vector<uint8_t>& use = lin.use;
  const double color_scale = std::sqrt(c.color_weight) / c.color_sigma;
  for (std::size_t p = 0; p < use.size(); ++p) {
    if (!use[p]) continue;
    const double alpha = render.alpha[p];
    for (int ch = 0; ch < 4; ++ch) {  // r, g, b, depth
      const bool is_depth = ch == 3;
      const double scale = is_depth ? 1.0 / c.depth_sigma : color_scale;
      if (scale == 0) continue;
      // Depth: the alpha-normalized render depth D / A, unbiased where A < 1.
      const double value = is_depth ? render.depth[p] / alpha : render.rgb[p * 3 + ch];
      const double r = scale * (value - (is_depth ? frame.depth[p] : frame.rgb[p * 3 + ch]));
      lin.cost += huber_cost(r, c.huber);
      if (!jacobian) continue;
      const double w = huber_weight(r, c.huber);
      auto row = [&](int out) {
        return Eigen::Map<const Eigen::Matrix<float, 6, 1>>(&(*jacobian)[(p * 5 + out) * 6]).cast<double>();
      };
      // d(D/A) = (dD - (D/A) dA) / A.
      const splat::Vector6d j = scale * (is_depth ? splat::Vector6d((row(3) - value * row(4)) / alpha) : splat::Vector6d(row(ch)));
      lin.h.selfadjointView<Eigen::Upper>().rankUpdate(j, w);
      lin.b += w * r * j;
    }
  }
  lin.h = lin.h.selfadjointView<Eigen::Upper>();
  return lin;
}

// Adam on the pose with the cost's gradient J^T W r; keeps the best pose seen.
void warm_up(splat::Rasterizer& rasterizer, const splat::GaussiansView& map, const splat::RgbdFrame& frame,
             const TrackingConfig& config, TrackingResult& result) {
  const splat::AdamHyper hyper{0.9, 0.999, 1e-12};
  double m[6] = {}, v[6] = {}, best = INFINITY;
  std::vector<float> jacobian;
  Eigen::Isometry3d best_pose = result.T_cam_world;
  for (int it = 0; it < config.warmup_iterations; ++it) {
    const splat::ForwardResult render = rasterizer.forward(map, splat::posed(frame.camera, result.T_cam_world), splat::images_only());
    ++result.renders;
    rasterizer.pose_jacobian(render, jacobian);
    const Linearization lin = linearize(render, &jacobian, frame, config);
    if (lin.overlap <= 0) break;
    // Mean cost per used pixel: the pixel set changes from step to step.
    const double mean_cost = lin.cost / std::max(1.0, static_cast<double>(std::count(lin.use.begin(), lin.use.end(), 1)));
    if (mean_cost < best) {
      best = mean_cost;
      best_pose = result.T_cam_world;
    }
    splat::Vector6d delta;
    const double t = it + 1;
    for (int k = 0; k < 6; ++k) {
      double step = 0;
      const double size = k < 3 ? config.warmup_step_translation : config.warmup_step_rotation;
      splat::adam_update(step, lin.b[k], m[k], v[k], size, 1 - std::pow(hyper.beta1, t), 1 - std::pow(hyper.beta2, t), hyper);
      delta[k] = step;
    }
    result.T_cam_world = splat::orthonormalized(splat::se3_exp(delta) * result.T_cam_world);
    ++result.iterations;
  }
  if (config.warmup_iterations > 0) result.T_cam_world = best_pose;
}

}  // namespace

TrackingResult track_frame(splat::Rasterizer& rasterizer, const splat::GaussiansView& map,
                           const splat::RgbdFrame& frame, const Eigen::Isometry3d& initial,
                           const TrackingConfig& config) {
  config.validate();
  if (frame.rgb.size() != static_cast<std::size_t>(frame.width()) * frame.height() * 3 ||
      frame.depth.size() != static_cast<std::size_t>(frame.width()) * frame.height()) {
    throw splat::Error("track_frame: frame images do not match its " + std::to_string(frame.width()) + "x" +
                       std::to_string(frame.height()) + " camera");
  }
  TrackingResult result;
  result.T_cam_world = initial;
  std::vector<float> jacobian;  // reused across levels and iterations
  for (std::size_t level = 0; level < config.pyramid.size(); ++level) {
    const splat::RgbdFrame scaled = splat::downsample(frame, config.pyramid[level]);
    TrackingConfig level_config = config;
    if (config.pyramid[level] > config.color_max_factor) level_config.color_weight = 0;
    auto render_at = [&](const Eigen::Isometry3d& pose) {
      ++result.renders;
      return rasterizer.forward(map, splat::posed(scaled.camera, pose), splat::images_only());
    };
    if (level == 0) warm_up(rasterizer, map, scaled, level_config, result);
    splat::ForwardResult render = render_at(result.T_cam_world);
    rasterizer.pose_jacobian(render, jacobian);
    Linearization lin = linearize(render, &jacobian, scaled, level_config);
    double lambda = 1e-4;  // Levenberg-Marquardt damping, relative to diag(H)
    for (int it = 0; it < config.iterations[level] && lin.overlap > 0; ++it) {
      Matrix6d damped = lin.h;
      damped.diagonal() += lambda * lin.h.diagonal().cwiseMax(1e-9);
      const splat::Vector6d delta = damped.ldlt().solve(-lin.b);
      if (!delta.allFinite()) break;
      const Eigen::Isometry3d candidate = splat::orthonormalized(splat::se3_exp(delta) * result.T_cam_world);
      splat::ForwardResult next = render_at(candidate);
      const double next_cost = linearize(next, nullptr, scaled, level_config, &lin.use).cost;
      if (next_cost < lin.cost) {
        result.T_cam_world = candidate;
        ++result.iterations;
        lambda = std::max(lambda / 4, 1e-7);
        const bool small = delta.head<3>().norm() < config.min_step_translation &&
                           delta.tail<3>().norm() < config.min_step_rotation;
        render = std::move(next);
        rasterizer.pose_jacobian(render, jacobian);
        lin = linearize(render, &jacobian, scaled, level_config);
        if (small) break;
      } else {
        lambda *= 8;  // rejected: trust the linearization less
        if (lambda > 1e6) break;
      }
    }
    result.final_cost = lin.cost;
    result.overlap = lin.overlap;
    result.median_depth_residual = lin.median_depth_residual;
  }
  if (result.overlap < config.min_overlap) {
    result.reason = "overlap " + std::to_string(result.overlap) + " below " + std::to_string(config.min_overlap);
  } else if (result.median_depth_residual > config.max_median_residual) {
    result.reason = "median depth residual " + std::to_string(result.median_depth_residual) + " m above " +
                    std::to_string(config.max_median_residual);
  }
  result.converged = result.reason.empty();
  return result;
}

}  // namespace tracking
