#include "mapping/mapper.h"

#include <algorithm>
#include <cmath>

#include "splat/adam.h"
#include "splat/error.h"
#include "splat/losses.h"
#include "splat/se3.h"

namespace mapping {

void MapperConfig::validate() const {
  auto fail = [](const std::string& what) { throw splat::Error("MapperConfig: " + what); };
  if (resolution_factor < 1 || refine_resolution_factor < 1) fail("resolution factors must be >= 1");
  if (iterations < 0 || window < 1 || max_keyframes < 1) fail("iterations >= 0, window >= 1, max_keyframes >= 1");
  if (!(prune_max_scale > 0)) fail("prune_max_scale must be positive");
  if (!(refine_learning_rate_scale > 0)) fail("refine_learning_rate_scale must be positive");
  for (double t : {depth_alpha_threshold, refine_depth_alpha_threshold}) {
    if (!(t >= 0 && t <= 1)) fail("depth_alpha_threshold and refine_depth_alpha_threshold must be in [0, 1]");
  }
  if (!(pose_learning_rate >= 0 && pose_rotation_learning_rate >= 0)) fail("pose learning rates must be >= 0");
}

Mapper::Mapper(splat::Rasterizer& rasterizer, const MapperConfig& config)
    : rasterizer_(rasterizer), config_(config), adam_(config.adam), rng_(config.random_seed) {
  config_.validate();
  map_.sh_degree = config_.seed.sh_degree;
}

std::size_t Mapper::densify(const Keyframe& kf) {
  const splat::RgbdFrame& f = kf.frame;
  std::vector<float> mask(f.depth.size(), 1.f);
  if (!map_.empty()) {
    const splat::ForwardResult render = rasterizer_.forward(map_, splat::posed(f.camera, kf.T_cam_world), splat::images_only());
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
  const std::size_t added = seed_from_depth(f, kf.T_cam_world.inverse(), config_.seed, map_, mask);
  adam_.append(added, map_.sh_degree);
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

void Mapper::step_pose(Eigen::Isometry3d& T_cam_world, PoseAdam& adam, const splat::PoseGradient& gradient,
                       double rate_scale) const {
  const bool moves = rate_scale > 0 && (config_.pose_learning_rate > 0 || config_.pose_rotation_learning_rate > 0);
  if (!moves) return;
  const splat::AdamHyper hyper{0.9, 0.999, 1e-12};
  const double t = ++adam.steps;
  splat::Vector6d delta = splat::Vector6d::Zero();
  for (int k = 0; k < 6; ++k) {
    const double rate = rate_scale * (k < 3 ? config_.pose_learning_rate : config_.pose_rotation_learning_rate);
    splat::adam_update(delta[k], gradient[k], adam.m[k], adam.v[k], rate, 1 - std::pow(hyper.beta1, t),
                       1 - std::pow(hyper.beta2, t), hyper);
  }
  T_cam_world = splat::orthonormalized(splat::se3_exp(delta) * T_cam_world);
}

double Mapper::optimize_step(Keyframe& kf, Step step, PoseAdam* pose) {
  const splat::RgbdFrame& f = kf.frame;
  const splat::ForwardResult render = rasterizer_.forward(map_, splat::posed(f.camera, kf.T_cam_world), splat::images_only());
  splat::ImageGrads d;
  d.rgb.assign(render.rgb.size(), 0.f);
  d.depth.assign(render.depth.size(), 0.f);
  double loss = splat::l1_loss<float>(render.rgb, f.rgb, 3, {}, d.rgb, config_.color_weight);
  if (config_.ssim_weight > 0) {
    loss += splat::dssim_loss<float>(render.rgb, f.rgb, f.width(), f.height(), 3, d.rgb, config_.ssim_weight);
  }
  d.alpha.assign(render.alpha.size(), 0.f);
  const double threshold = step == Step::kWindow ? config_.depth_alpha_threshold : config_.refine_depth_alpha_threshold;
  loss += splat::silhouette_depth_l1_loss<float>(render.depth, render.alpha, f.depth, threshold, d.depth, d.alpha,
                                                 config_.depth_weight);
  splat::BackwardResult backward = rasterizer_.backward(render, d);
  if (step == Step::kWindow && kf.number != 0) {  // the first keyframe is the world frame
    step_pose(kf.T_cam_world, kf.pose, backward.d_loss_d_pose, 1.0);
  } else if (step == Step::kRefine && pose) {
    step_pose(kf.T_cam_world, *pose, backward.d_loss_d_pose, config_.refine_pose_rate_scale);
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

std::size_t Mapper::prune() {
  std::vector<uint8_t> keep(map_.size(), 1);
  const float min_logit = static_cast<float>(std::log(config_.prune_opacity / (1 - config_.prune_opacity)));
  const float max_log_scale = static_cast<float>(std::log(config_.prune_max_scale));
  std::size_t removed = 0;
  for (std::size_t i = 0; i < map_.size(); ++i) {
    const float largest = std::max({map_.log_scales[i * 3], map_.log_scales[i * 3 + 1], map_.log_scales[i * 3 + 2]});
    if (map_.opacity_logits[i] < min_logit || largest > max_log_scale) {
      keep[i] = 0;
      ++removed;
    }
  }
  if (removed > 0) {
    remove_gaussians(map_, keep);
    adam_.remove(keep);
  }
  return removed;
}

double Mapper::refine(const splat::RgbdFrame& frame, Eigen::Isometry3d& T_cam_world, PoseAdam* pose, int iterations) {
  if (map_.empty()) return 0;
  Keyframe kf{splat::downsample(frame, config_.refine_resolution_factor), T_cam_world};
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

MappingStats Mapper::add_keyframe(const splat::RgbdFrame& frame, const Eigen::Isometry3d& T_cam_world) {
  MappingStats stats;
  keyframes_.push_back({splat::downsample(frame, config_.resolution_factor), T_cam_world, added_++});
  Keyframe& newest = keyframes_.back();
  stats.added = densify(newest);
  const std::vector<Keyframe*> window = window_for(newest);
  stats.window = window.size();
  // Half the steps on the new keyframe, the rest spread over the window at random.
  std::uniform_int_distribution<std::size_t> pick(0, window.size() - 1);
  for (int it = 0; it < config_.iterations && !map_.empty(); ++it) {
    Keyframe& kf = it % 2 == 0 ? newest : *window[pick(rng_)];
    stats.final_loss = optimize_step(kf, Step::kWindow, nullptr);
    ++stats.iterations;
  }
  stats.pruned = prune();
  // Bounded memory: drop the oldest stored keyframe (the recent ones are the covisible ones
  // in a continuous sequence).
  if (keyframes_.size() > config_.max_keyframes) keyframes_.pop_front();
  return stats;
}

}  // namespace mapping
