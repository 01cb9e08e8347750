#include "mapping/mapper.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "mapping/depth_holes.h"
#include "splat/adam.h"
#include "splat/error.h"
#include "splat/field_check.h"
#include "splat/losses.h"
#include "splat/se3.h"

namespace mapping {

void MapperConfig::validate(const std::string& prefix) const {
  const splat::FieldCheck check(prefix);
  check.at_least("resolution_factor", resolution_factor, 1);
  check.at_least("refine_resolution_factor", refine_resolution_factor, 1);
  check.at_least("iterations", iterations, 0);
  check.at_least("window", window, 1);
  check.at_least("max_keyframes", max_keyframes, std::size_t{1});
  check.at_least("color_weight", color_weight, 0.0);
  check.at_least("ssim_weight", ssim_weight, 0.0);
  check.at_least("depth_weight", depth_weight, 0.0);
  check.at_least("refine_depth_weight", refine_depth_weight, 0.0);
  check.in_range("depth_alpha_threshold", depth_alpha_threshold, 0.0, 1.0);
  check.in_range("refine_depth_alpha_threshold", refine_depth_alpha_threshold, 0.0, 1.0);
  check.positive("refine_learning_rate_scale", refine_learning_rate_scale);
  check.at_least("refine_pose_learning_rate", refine_pose_learning_rate, 0.0);
  check.at_least("refine_pose_rotation_learning_rate", refine_pose_rotation_learning_rate, 0.0);
  check.at_least("refine_vignetting_rate", refine_vignetting_rate, 0.0);
  check.in_range("densify_alpha", densify_alpha, 0.0, 1.0);
  check.positive("depth_error_factor", depth_error_factor);
  check.at_least("seed_stride", seed.stride, 1);
  check.in_range("seed_opacity", seed.opacity, 1e-6, 1.0 - 1e-6);
  check.positive("seed_scale_factor", seed.scale_factor);
  check.in_range("sh_degree", seed.sh_degree, 0, 3);
  check.in_range("prune_opacity", prune_opacity, 0.0, 1.0 - 1e-6);
  check.at_least("ghost_views", ghost_views, 1);
  check.at_least("free_space_margin", free_space_margin, 0.0);
  check.positive("prune_max_scale", prune_max_scale);
  check.at_least("pose_learning_rate", pose_learning_rate, 0.0);
  check.at_least("pose_rotation_learning_rate", pose_rotation_learning_rate, 0.0);
}

Mapper::Mapper(splat::Rasterizer& rasterizer, const MapperConfig& config)
    : rasterizer_(rasterizer), config_(config), adam_(config.adam), rng_(config.random_seed) {
  config_.validate();
  map_.sh_degree = config_.seed.sh_degree;
}

std::size_t Mapper::densify(const splat::RgbdFrame& f, const Eigen::Isometry3d& T_cam_world, bool fill_holes,
                            std::size_t anchor) {
  std::vector<float> mask(f.depth.size(), 1.f);
  if (!map_.empty()) {
    const splat::ForwardResult render = rasterizer_.forward(map_, splat::posed(f.camera, T_cam_world), splat::images_only());
    std::vector<float> errors;
    for (std::size_t p = 0; p < f.depth.size(); ++p) {
      if (f.depth[p] > 0 && render.alpha[p] > config_.densify_alpha) errors.push_back(std::abs(render.depth_normalized[p] - f.depth[p]));
    }
    float median = 0;
    if (!errors.empty()) {
      std::nth_element(errors.begin(), errors.begin() + static_cast<long>(errors.size() / 2), errors.end());
      median = errors[errors.size() / 2];
    }
    for (std::size_t p = 0; p < mask.size(); ++p) {
      const bool uncovered = render.alpha[p] < config_.densify_alpha;
      // Something measured in front of the map that the map does not have.
      const bool in_front = f.depth[p] > 0 && render.depth_normalized[p] - f.depth[p] > config_.depth_error_factor * std::max(median, 1e-3f);
      mask[p] = uncovered || in_front ? 1.f : 0.f;
    }
  }
  if (!f.ignore.empty()) {
    for (std::size_t p = 0; p < mask.size(); ++p) {
      if (f.ignore[p]) mask[p] = 0.f;
    }
  }
  splat::RgbdFrame filled;
  if (fill_holes) {
    filled = f;
    filled.depth = fill_depth_holes(f.depth, f.width(), f.height());
  }
  const std::size_t added = seed_from_depth(fill_holes ? filled : f, T_cam_world.inverse(), config_.seed, map_, mask);
  adam_.append(added, map_.sh_degree);
  anchors_.resize(map_.size(), static_cast<uint32_t>(anchor));
  seen_through_.resize(map_.size(), 0);
  seen_on_.resize(map_.size(), 0);
  return added;
}

// The newest keyframe plus the stored ones whose cameras are closest in position and viewing
// direction (a cheap covisibility score), up to the window size.
std::vector<Mapper::Keyframe*> Mapper::window_for(Keyframe& newest) {
  const Eigen::Isometry3d newest_world = newest.T_cam_world.inverse();
  std::vector<std::pair<double, Keyframe*>> scored;
  for (Keyframe& kf : keyframes_) {
    if (&kf == &newest) continue;
    const Eigen::Isometry3d world = kf.T_cam_world.inverse();
    const double distance = (world.translation() - newest_world.translation()).norm();
    const double angle = std::acos(std::clamp(world.linear().col(2).dot(newest_world.linear().col(2)), -1.0, 1.0));
    scored.emplace_back(distance + 0.5 * angle, &kf);  // 0.5 m per radian
  }
  std::sort(scored.begin(), scored.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<Keyframe*> window = {&newest};
  for (const auto& [score, kf] : scored) {
    if (window.size() >= static_cast<std::size_t>(config_.window)) break;
    window.push_back(kf);
  }
  return window;
}

namespace {

// One Adam step of a few camera parameters (a pose's six, the vignetting's two), each with its
// own rate; `steps` counts this state's steps.
void adam_step(int n, double* params, const double* gradient, const double* rates, double* m, double* v, int& steps) {
  const splat::AdamHyper hyper{0.9, 0.999, 1e-12};
  const double t = ++steps;
  for (int k = 0; k < n; ++k) {
    splat::adam_update(params[k], gradient[k], m[k], v[k], rates[k], 1 - std::pow(hyper.beta1, t),
                       1 - std::pow(hyper.beta2, t), hyper);
  }
}

}  // namespace

void Mapper::step_pose(Eigen::Isometry3d& T_cam_world, PoseAdam& adam, const splat::PoseGradient& gradient,
                       double translation_rate, double rotation_rate) const {
  if (!(translation_rate > 0 || rotation_rate > 0)) return;
  double rates[6];
  for (int k = 0; k < 6; ++k) rates[k] = k < 3 ? translation_rate : rotation_rate;
  splat::Vector6d delta = splat::Vector6d::Zero();
  adam_step(6, delta.data(), gradient.data(), rates, adam.m.data(), adam.v.data(), adam.steps);
  T_cam_world = splat::orthonormalized(splat::se3_exp(delta) * T_cam_world);
}

void Mapper::step_vignetting(const std::array<double, 2>& gradient) {
  double k[2] = {vignetting_.k1, vignetting_.k2};
  const double rates[2] = {config_.refine_vignetting_rate, config_.refine_vignetting_rate};
  adam_step(2, k, gradient.data(), rates, vignetting_adam_.m.data(), vignetting_adam_.v.data(),
            vignetting_adam_.steps);
  vignetting_.k1 = k[0];
  vignetting_.k2 = k[1];
}

double Mapper::optimize_step(Keyframe& kf, Step step, PoseAdam* pose) {
  const splat::RgbdFrame& f = kf.frame;
  const splat::ForwardResult render = rasterizer_.forward(map_, splat::posed(f.camera, kf.T_cam_world), splat::images_only());
  splat::ImageGrads d;
  d.rgb.assign(render.rgb.size(), 0.f);
  d.depth.assign(render.depth.size(), 0.f);
  // The colour losses compare what the camera records: the render through its vignetting.
  const bool learn_vignetting = step == Step::kRefine && config_.refine_vignetting_rate > 0;
  const bool vignetted = learn_vignetting || vignetting_.k1 != 0 || vignetting_.k2 != 0;
  std::vector<float> recorded;
  if (vignetted) {
    recorded = render.rgb;
    vignetting_.apply(recorded, f.camera);
  }
  const std::vector<float>& colour = vignetted ? recorded : render.rgb;
  // Ignored pixels (moving objects) take the render's own values as targets: they pull nowhere.
  std::vector<float> ignoring_rgb, ignoring_depth;
  if (!f.ignore.empty()) {
    ignoring_rgb = f.rgb;
    ignoring_depth = f.depth;
    for (std::size_t p = 0; p < f.ignore.size(); ++p) {
      if (!f.ignore[p]) continue;
      for (int c = 0; c < 3; ++c) ignoring_rgb[p * 3 + c] = colour[p * 3 + c];
      ignoring_depth[p] = 0;  // no measurement
    }
  }
  const std::vector<float>& target_rgb = f.ignore.empty() ? f.rgb : ignoring_rgb;
  const std::vector<float>& target_depth = f.ignore.empty() ? f.depth : ignoring_depth;
  double loss = splat::l1_loss<float>(colour, target_rgb, 3, {}, d.rgb, config_.color_weight);
  if (config_.ssim_weight > 0) {
    loss += splat::dssim_loss<float>(colour, target_rgb, f.width(), f.height(), 3, d.rgb, config_.ssim_weight);
  }
  if (vignetted) {
    const std::array<double, 2> d_vignetting = vignetting_.backward(render.rgb, d.rgb, f.camera);
    if (learn_vignetting) step_vignetting(d_vignetting);
  }
  d.alpha.assign(render.alpha.size(), 0.f);
  const double threshold = step == Step::kWindow ? config_.depth_alpha_threshold : config_.refine_depth_alpha_threshold;
  loss += splat::silhouette_depth_l1_loss<float>(render.depth, render.alpha, target_depth, threshold, d.depth, d.alpha,
                                                 step == Step::kWindow ? config_.depth_weight : config_.refine_depth_weight);
  splat::BackwardResult backward = rasterizer_.backward(render, d);
  if (step == Step::kWindow && kf.number != 0) {  // the first keyframe is the world frame
    step_pose(kf.T_cam_world, kf.pose, backward.d_loss_d_pose, config_.pose_learning_rate, config_.pose_rotation_learning_rate);
  } else if (step == Step::kRefine && pose) {
    step_pose(kf.T_cam_world, *pose, backward.d_loss_d_pose, config_.refine_pose_learning_rate,
              config_.refine_pose_rotation_learning_rate);
  }
  splat::GaussianGrads& grads = backward.d_gaussians;
  if (config_.isotropic) {
    // The three log scales move together (they start equal) and rotations stay fixed.
    for (std::size_t i = 0; i < grads.size(); ++i) {
      float* g = &grads.log_scales[i * 3];
      const float mean = (g[0] + g[1] + g[2]) / 3;
      g[0] = g[1] = g[2] = mean;
    }
    std::fill(grads.rotations.begin(), grads.rotations.end(), 0.f);
  }
  adam_.step(map_, grads, step == Step::kWindow ? 1.0 : config_.refine_learning_rate_scale);
  return loss;
}

void Mapper::observe_free_space(const splat::RgbdFrame& f, const Eigen::Isometry3d& T_cam_world, std::size_t first) {
  const int w = f.width(), h = f.height();
  const Eigen::Matrix3f r = T_cam_world.linear().cast<float>();
  const Eigen::Vector3f t = T_cam_world.translation().cast<float>();
  seen_through_.resize(map_.size(), 0);
  seen_on_.resize(map_.size(), 0);
  for (std::size_t i = first; i < map_.size(); ++i) {
    const Eigen::Vector3f p = r * Eigen::Vector3f(map_.means[i * 3], map_.means[i * 3 + 1], map_.means[i * 3 + 2]) + t;
    if (!(p.z() > 0.1f)) continue;
    const float u = static_cast<float>(f.camera.fx) * p.x() / p.z() + static_cast<float>(f.camera.cx);
    const float v = static_cast<float>(f.camera.fy) * p.y() / p.z() + static_cast<float>(f.camera.cy);
    if (!(u >= 1 && v >= 1 && u < static_cast<float>(w - 1) && v < static_cast<float>(h - 1))) continue;
    const int x = static_cast<int>(u), y = static_cast<int>(v);
    const float margin = static_cast<float>(config_.free_space_margin) + 0.02f * p.z();
    bool through = true, measured = true, on = false;
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const std::size_t j = static_cast<std::size_t>(y + dy) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x + dx);
        const float z = f.depth[j];
        if (!(z > 0) || (!f.ignore.empty() && f.ignore[j])) {
          measured = false;
          continue;
        }
        through = through && z > p.z() + margin;
        on = on || std::abs(z - p.z()) <= margin;
      }
    }
    if (!measured) continue;
    if (through && seen_through_[i] < UINT16_MAX) ++seen_through_[i];
    if (on && seen_on_[i] < UINT16_MAX) ++seen_on_[i];
  }
}

Mapper::Pruned Mapper::prune() {
  std::vector<uint8_t> keep(map_.size(), 1);
  seen_through_.resize(map_.size(), 0);
  seen_on_.resize(map_.size(), 0);
  const float min_logit = static_cast<float>(std::log(config_.prune_opacity / (1 - config_.prune_opacity)));
  const float max_log_scale = static_cast<float>(std::log(config_.prune_max_scale));
  Pruned removed;
  for (std::size_t i = 0; i < map_.size(); ++i) {
    const float largest = std::max({map_.log_scales[i * 3], map_.log_scales[i * 3 + 1], map_.log_scales[i * 3 + 2]});
    const bool ghost = seen_through_[i] >= config_.ghost_views && seen_through_[i] > 2 * seen_on_[i];
    if (map_.opacity_logits[i] < min_logit || largest > max_log_scale || ghost) {
      keep[i] = 0;
      ++removed.gaussians;
      removed.ghosts += ghost;
    }
  }
  if (removed.gaussians > 0) {
    remove_gaussians(map_, keep);
    adam_.remove(keep);
    std::size_t out = 0;
    for (std::size_t i = 0; i < keep.size(); ++i)
      if (keep[i]) anchors_[out] = anchors_[i], seen_through_[out] = seen_through_[i], seen_on_[out++] = seen_on_[i];
    anchors_.resize(out);
    seen_through_.resize(out);
    seen_on_.resize(out);
  }
  return removed;
}

splat::RgbdFrame Mapper::refinement_frame(const splat::RgbdFrame& frame) const {
  return splat::downsample(frame, config_.refine_resolution_factor);
}

double Mapper::refine(const splat::RgbdFrame& refinement_frame, Eigen::Isometry3d& T_cam_world, PoseAdam* pose,
                      int iterations, bool densify_first) {
  if (map_.empty()) return 0;
  Keyframe kf{refinement_frame, T_cam_world};
  if (densify_first) densify(kf.frame, kf.T_cam_world, config_.refine_seed_depth_holes, added_ > 0 ? added_ - 1 : 0);
  double loss = 0;
  for (int it = 0; it < iterations; ++it) loss = optimize_step(kf, Step::kRefine, pose);
  T_cam_world = kf.T_cam_world;
  return loss;
}

std::vector<std::pair<std::size_t, Eigen::Isometry3d>> Mapper::keyframe_poses() const {
  std::vector<std::pair<std::size_t, Eigen::Isometry3d>> poses;
  for (const Keyframe& kf : keyframes_) poses.emplace_back(kf.number, kf.T_cam_world);
  return poses;
}

MapperState Mapper::state() const {
  MapperState s;
  s.map = map_;
  s.adam = adam_.state();
  for (const Keyframe& kf : keyframes_) s.keyframes.push_back({kf.number, kf.T_cam_world, kf.pose});
  s.vignetting = vignetting_;
  s.vignetting_m = vignetting_adam_.m;
  s.vignetting_v = vignetting_adam_.v;
  s.vignetting_steps = vignetting_adam_.steps;
  s.added = added_;
  s.anchors = anchors_;
  s.seen_through = seen_through_;
  s.seen_on = seen_on_;
  std::ostringstream rng;
  rng << rng_;
  s.rng = rng.str();
  return s;
}

void Mapper::restore(MapperState s, const std::function<splat::RgbdFrame(std::size_t number)>& load) {
  splat::validate(splat::GaussiansView(s.map), "checkpointed map");
  if (s.adam.steps.size() != s.map.size() && !(s.adam.steps.empty() && s.adam.m.empty())) {
    throw splat::Error("Mapper::restore: optimizer state for " + std::to_string(s.adam.steps.size()) +
                       " Gaussians, map of " + std::to_string(s.map.size()));
  }
  if (s.keyframes.size() > config_.max_keyframes || s.keyframes.size() > s.added) {
    throw splat::Error("Mapper::restore: " + std::to_string(s.keyframes.size()) + " stored keyframes of " +
                       std::to_string(s.added) + " added (at most " + std::to_string(config_.max_keyframes) + ")");
  }
  if (s.seen_through.size() != s.map.size() || s.seen_on.size() != s.map.size()) {
    throw splat::Error("Mapper::restore: free-space counts for " + std::to_string(s.seen_through.size()) + " and " +
                       std::to_string(s.seen_on.size()) + " Gaussians, the map has " + std::to_string(s.map.size()));
  }
  if (s.anchors.size() != s.map.size()) {
    throw splat::Error("Mapper::restore: " + std::to_string(s.anchors.size()) + " anchors for " +
                       std::to_string(s.map.size()) + " Gaussians");
  }
  for (uint32_t a : s.anchors) {
    if (a >= std::max<std::size_t>(s.added, 1)) throw splat::Error("Mapper::restore: a Gaussian anchored to keyframe " + std::to_string(a) + " of " + std::to_string(s.added));
  }
  std::istringstream rng(s.rng);
  std::mt19937 restored_rng;
  if (!(rng >> restored_rng)) throw splat::Error("Mapper::restore: unreadable random generator state");
  std::deque<Keyframe> keyframes;
  for (const MapperState::Keyframe& kf : s.keyframes) {
    if (kf.number >= s.added) {
      throw splat::Error("Mapper::restore: keyframe number " + std::to_string(kf.number) + " of " +
                         std::to_string(s.added) + " added");
    }
    keyframes.push_back({splat::downsample(load(kf.number), config_.resolution_factor), kf.T_cam_world, kf.number, kf.pose});
  }
  adam_.restore(std::move(s.adam));
  map_ = std::move(s.map);
  keyframes_ = std::move(keyframes);
  vignetting_ = s.vignetting;
  vignetting_adam_.m = s.vignetting_m;
  vignetting_adam_.v = s.vignetting_v;
  vignetting_adam_.steps = s.vignetting_steps;
  added_ = s.added;
  anchors_ = std::move(s.anchors);
  seen_through_ = std::move(s.seen_through);
  seen_on_ = std::move(s.seen_on);
  rng_ = restored_rng;
}

void Mapper::correct_keyframes(const std::vector<Eigen::Isometry3d>& world_correction) {
  if (world_correction.size() != added_) {
    throw splat::Error("Mapper::correct_keyframes: " + std::to_string(world_correction.size()) + " corrections for " +
                       std::to_string(added_) + " keyframes");
  }
  std::vector<Eigen::Quaternionf> rotation;
  for (const auto& C : world_correction) rotation.emplace_back(Eigen::Quaterniond(C.linear()).cast<float>());
  for (std::size_t i = 0; i < map_.size(); ++i) {
    const std::size_t k = anchors_[i];
    const Eigen::Isometry3d& C = world_correction[k];
    // (Higher SH bands would turn with the Gaussian too; loop corrections turn by degrees.)
    float* m = &map_.means[i * 3];
    const Eigen::Vector3d moved = C * Eigen::Vector3d(m[0], m[1], m[2]);
    for (int a = 0; a < 3; ++a) m[a] = static_cast<float>(moved[a]);
    float* q = &map_.rotations[i * 4];  // w, x, y, z
    const Eigen::Quaternionf turned = rotation[k] * Eigen::Quaternionf(q[0], q[1], q[2], q[3]);
    q[0] = turned.w(), q[1] = turned.x(), q[2] = turned.y(), q[3] = turned.z();
  }
  for (Keyframe& kf : keyframes_) kf.T_cam_world = splat::orthonormalized(kf.T_cam_world * world_correction[kf.number].inverse());
}

MappingStats Mapper::add_keyframe(const splat::RgbdFrame& frame, const Eigen::Isometry3d& T_cam_world) {
  MappingStats stats;
  keyframes_.push_back({splat::downsample(frame, config_.resolution_factor), T_cam_world, added_++});
  Keyframe& newest = keyframes_.back();
  observe_free_space(newest.frame, newest.T_cam_world);
  stats.added = densify(newest.frame, newest.T_cam_world, false, newest.number);
  const std::vector<Keyframe*> window = window_for(newest);
  stats.window = window.size();
  // Half the steps on the new keyframe, the rest spread over the window at random.
  std::uniform_int_distribution<std::size_t> pick(0, window.size() - 1);
  for (int it = 0; it < config_.iterations && !map_.empty(); ++it) {
    Keyframe& kf = it % 2 == 0 ? newest : *window[pick(rng_)];
    stats.final_loss = optimize_step(kf, Step::kWindow, nullptr);
    ++stats.iterations;
  }
  const Pruned pruned = prune();
  stats.pruned = pruned.gaussians;
  stats.ghosts = pruned.ghosts;
  // Bounded memory: drop the oldest stored keyframe (the recent ones are the covisible ones
  // in a continuous sequence).
  if (keyframes_.size() > config_.max_keyframes) keyframes_.pop_front();
  return stats;
}

}  // namespace mapping
