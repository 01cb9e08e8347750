#include "mapping/mapper.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "mapping/depth_holes.h"
#include "splat/adam.h"
#include "splat/error.h"
#include "splat/field_check.h"
#include "splat/losses.h"
#include "splat/se3.h"

namespace mapping {
namespace {

// The resident map's keys: keyframes are stored under their numbers, the frame refine() fits
// under kRefineTarget, and the sweep's cached frames under kSweepFrames + their id.
constexpr uint64_t kRefineTarget = ~uint64_t{0};
constexpr uint64_t kSweepFrames = uint64_t{1} << 62;

}  // namespace

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
  check.at_least("sweep_device_cache_mib", sweep_device_cache_mib, 0.0);
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
  if (config_.device_resident) device_ = rasterizer.make_resident_map(config_.seed.sh_degree);
}

const splat::Gaussians& Mapper::map() const {
  pull_from_device(false);
  return map_;
}

void Mapper::pull_from_device(bool moments) const {
  if (!device_ || (host_current_ && (host_adam_current_ || !moments))) return;
  if (moments) {
    splat::AdamMoments m;
    device_->read(map_, &m);
    adam_.restore({std::move(m.m), std::move(m.v), std::move(m.steps)});
    host_adam_current_ = true;
  } else {
    device_->read(map_, nullptr);
  }
  host_current_ = true;
}

void Mapper::push_to_device() {
  if (!device_) return;
  const GaussianAdam::State adam = adam_.state();
  const splat::AdamMoments moments{adam.m, adam.v, adam.steps};
  // A map never stepped has no optimizer state yet: it starts from zero moments.
  device_->assign(map_, adam.steps.size() == map_.size() ? &moments : nullptr);
  host_current_ = host_adam_current_ = true;
}


std::size_t Mapper::densify(const splat::RgbdFrame& f, uint64_t device_key, const Eigen::Isometry3d& T_cam_world,
                            bool fill_holes, std::size_t anchor) {
  std::vector<float> mask(f.depth.size(), 1.f);
  // In float, as the device's test (splat::ResidentMap::coverage_mask) computes it.
  const float densify_alpha = static_cast<float>(config_.densify_alpha);
  const float depth_error_factor = static_cast<float>(config_.depth_error_factor), min_median = 1e-3f;
  if (size() > 0 && device_) {
    const splat::Camera camera = splat::posed(f.camera, T_cam_world);
    const std::vector<uint8_t> seed = device_->coverage_mask(device_key, camera, {densify_alpha, depth_error_factor, min_median});
    for (std::size_t p = 0; p < mask.size(); ++p) mask[p] = seed[p];
  } else if (size() > 0) {
    const splat::ForwardResult render = rasterizer_.forward(map_, splat::posed(f.camera, T_cam_world), splat::images_only());
    std::vector<float> errors;
    for (std::size_t p = 0; p < f.depth.size(); ++p) {
      if (f.depth[p] > 0 && render.alpha[p] > densify_alpha) errors.push_back(std::abs(render.depth_normalized[p] - f.depth[p]));
    }
    float median = 0;
    if (!errors.empty()) {
      std::nth_element(errors.begin(), errors.begin() + static_cast<long>(errors.size() / 2), errors.end());
      median = errors[errors.size() / 2];
    }
    const float threshold = depth_error_factor * std::max(median, min_median);
    for (std::size_t p = 0; p < mask.size(); ++p) {
      const bool uncovered = render.alpha[p] < densify_alpha;
      // Something measured in front of the map that the map does not have.
      const bool in_front = f.depth[p] > 0 && render.depth_normalized[p] - f.depth[p] > threshold;
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
  const splat::RgbdFrame& seeded = fill_holes ? filled : f;
  std::size_t added = 0;
  if (device_) {
    splat::Gaussians seeds;
    seeds.sh_degree = config_.seed.sh_degree;
    added = seed_from_depth(seeded, T_cam_world.inverse(), config_.seed, seeds, mask);
    if (added > 0) {
      device_->append(seeds);
      device_changed();
    }
  } else {
    added = seed_from_depth(seeded, T_cam_world.inverse(), config_.seed, map_, mask);
    adam_.append(added, map_.sh_degree);
  }
  anchors_.resize(size(), static_cast<uint32_t>(anchor));
  seen_through_.resize(size(), 0);
  seen_on_.resize(size(), 0);
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

double Mapper::optimize_step(Keyframe& kf, Step step, PoseAdam* pose, uint64_t device_key,
                             double rate_scale) {
  const splat::MappingStepResult result =
      device_ ? device_step(kf, device_key, step, rate_scale) : host_step(kf, step, rate_scale);
  if (step == Step::kRefine && config_.refine_vignetting_rate > 0) step_vignetting(result.d_loss_d_vignetting);
  if (step == Step::kWindow && kf.number != 0) {  // the first keyframe is the world frame
    step_pose(kf.T_cam_world, kf.pose, result.d_loss_d_pose, config_.pose_learning_rate, config_.pose_rotation_learning_rate);
  } else if (step == Step::kRefine && pose) {
    step_pose(kf.T_cam_world, *pose, result.d_loss_d_pose, config_.refine_pose_learning_rate,
              config_.refine_pose_rotation_learning_rate);
  }
  return result.loss;
}

splat::MappingStepResult Mapper::device_step(const Keyframe& kf, uint64_t key, Step step,
                                             double rate_scale) {
  splat::MappingLoss loss;
  loss.color_weight = config_.color_weight;
  loss.ssim_weight = config_.ssim_weight;
  loss.depth_weight = step == Step::kWindow ? config_.depth_weight : config_.refine_depth_weight;
  loss.depth_alpha_threshold = step == Step::kWindow ? config_.depth_alpha_threshold : config_.refine_depth_alpha_threshold;
  loss.vignetting_k1 = vignetting_.k1;
  loss.vignetting_k2 = vignetting_.k2;
  const AdamConfig& a = adam_.config();
  const splat::AdamRates rates{a.means, a.log_scales, a.rotations, a.opacity_logits, a.sh_dc, a.sh_rest, a.hyper};
  const splat::MappingStepResult result =
      device_->step(key, splat::posed(kf.frame.camera, kf.T_cam_world), loss, rates, rate_scale,
                    config_.isotropic);
  device_changed();
  return result;
}

splat::MappingStepResult Mapper::host_step(const Keyframe& kf, Step step, double rate_scale) {
  const splat::RgbdFrame& f = kf.frame;
  // The views across the exposure, and the images the camera would have recorded: their mean.
  const int samples = kf.motion.samples;
  std::vector<splat::ForwardResult> views;
  for (int k = 0; k < samples; ++k) {
    const double at = samples > 1 ? (k + 0.5) / samples - 0.5 : 0.0;  // in exposures from mid-exposure
    const Eigen::Isometry3d T_cam_world = splat::se3_exp(-at * kf.motion.twist) * kf.T_cam_world;
    views.push_back(rasterizer_.forward(map_, splat::posed(f.camera, T_cam_world), splat::images_only()));
  }
  splat::ForwardResult mean;
  if (samples > 1) {
    for (auto field : {&splat::ForwardResult::rgb, &splat::ForwardResult::depth, &splat::ForwardResult::alpha}) {
      std::vector<float>& out = mean.*field;
      out.assign((views[0].*field).size(), 0.f);
      for (const splat::ForwardResult& v : views) {
        for (std::size_t p = 0; p < out.size(); ++p) out[p] += (v.*field)[p] / static_cast<float>(samples);
      }
    }
  }
  const splat::ForwardResult& render = samples > 1 ? mean : views[0];
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
  splat::MappingStepResult result;
  result.loss = splat::l1_loss<float>(colour, target_rgb, 3, {}, d.rgb, config_.color_weight);
  if (config_.ssim_weight > 0) {
    result.loss += splat::dssim_loss<float>(colour, target_rgb, f.width(), f.height(), 3, d.rgb, config_.ssim_weight,
                                            rasterizer_.host_threads());
  }
  if (vignetted) result.d_loss_d_vignetting = vignetting_.backward(render.rgb, d.rgb, f.camera);
  d.alpha.assign(render.alpha.size(), 0.f);
  const double threshold = step == Step::kWindow ? config_.depth_alpha_threshold : config_.refine_depth_alpha_threshold;
  result.loss += splat::silhouette_depth_l1_loss<float>(render.depth, render.alpha, target_depth, threshold, d.depth, d.alpha,
                                                        step == Step::kWindow ? config_.depth_weight : config_.refine_depth_weight);
  // Each view carries its share of the mean's gradient; the pose's is summed over them.
  if (samples > 1) {
    for (auto field : {&splat::ImageGrads::rgb, &splat::ImageGrads::depth, &splat::ImageGrads::alpha}) {
      for (float& g : d.*field) g /= static_cast<float>(samples);
    }
  }
  splat::BackwardResult backward = rasterizer_.backward(views[0], d);
  for (int k = 1; k < samples; ++k) {
    const splat::BackwardResult view = rasterizer_.backward(views[k], d);
    backward.d_loss_d_pose += view.d_loss_d_pose;
    for (const splat::ParamGroup group : splat::kAllParamGroups) {
      std::vector<float>& into = splat::param_group(backward.d_gaussians, group);
      const std::vector<float>& add = splat::param_group(view.d_gaussians, group);
      for (std::size_t i = 0; i < into.size(); ++i) into[i] += add[i];
    }
  }
  result.d_loss_d_pose = backward.d_loss_d_pose;
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
  adam_.step(map_, grads, rate_scale, rasterizer_.host_threads());
  return result;
}

splat::ResidentMap::FreeSpaceTest Mapper::free_space_test() const {
  // Centres nearer than 10 cm get no verdict; the margin grows 2% a metre, with depth noise.
  return {0.1f, static_cast<float>(config_.free_space_margin), 0.02f};
}

void Mapper::observe_free_space(const splat::RgbdFrame& f, const Eigen::Isometry3d& T_cam_world, std::size_t first) {
  const int w = f.width(), h = f.height();
  const Eigen::Matrix3f r = T_cam_world.linear().cast<float>();
  const Eigen::Vector3f t = T_cam_world.translation().cast<float>();
  const splat::ResidentMap::FreeSpaceTest test = free_space_test();
  // The means alone, kept until the device map changes: the sweep asks for every frame.
  if (device_ && !host_current_ && !means_cached_) {
    device_means_ = device_->read_group(splat::ParamGroup::kMeans);
    means_cached_ = true;
  }
  const std::vector<float>& means = device_ && !host_current_ ? device_means_ : map_.means;
  const std::size_t n = size();
  std::vector<splat::FreeSpace> verdicts(n > first ? n - first : 0, splat::FreeSpace::kNone);
  for (std::size_t i = first; i < n; ++i) {
    const Eigen::Vector3f p = r * Eigen::Vector3f(means[i * 3], means[i * 3 + 1], means[i * 3 + 2]) + t;
    if (!(p.z() > test.near_z)) continue;
    const float u = static_cast<float>(f.camera.fx) * p.x() / p.z() + static_cast<float>(f.camera.cx);
    const float v = static_cast<float>(f.camera.fy) * p.y() / p.z() + static_cast<float>(f.camera.cy);
    if (!(u >= 1 && v >= 1 && u < static_cast<float>(w - 1) && v < static_cast<float>(h - 1))) continue;
    const int x = static_cast<int>(u), y = static_cast<int>(v);
    const float margin = test.margin + test.margin_per_metre * p.z();
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
    if (measured) verdicts[i - first] = through ? splat::FreeSpace::kThrough : on ? splat::FreeSpace::kOn : splat::FreeSpace::kNone;
  }
  count_free_space(verdicts, first);
}

void Mapper::count_free_space(const std::vector<splat::FreeSpace>& verdicts, std::size_t first) {
  seen_through_.resize(size(), 0);
  seen_on_.resize(size(), 0);
  for (std::size_t j = 0; j < verdicts.size(); ++j) {
    const std::size_t i = first + j;
    if (verdicts[j] == splat::FreeSpace::kThrough && seen_through_[i] < UINT16_MAX) ++seen_through_[i];
    if (verdicts[j] == splat::FreeSpace::kOn && seen_on_[i] < UINT16_MAX) ++seen_on_[i];
  }
}

Mapper::Pruned Mapper::prune(bool oversized) {
  const std::size_t n = size();
  std::vector<uint8_t> keep(n, 1);
  seen_through_.resize(n, 0);
  seen_on_.resize(n, 0);
  const float min_logit = static_cast<float>(std::log(config_.prune_opacity / (1 - config_.prune_opacity)));
  const float max_log_scale = oversized ? static_cast<float>(std::log(config_.prune_max_scale)) : std::numeric_limits<float>::infinity();
  // Faint or oversized: tested where the map is.
  std::vector<uint8_t> removable;
  if (device_ && !host_current_) {
    removable = device_->faint_or_oversized(min_logit, max_log_scale);
  } else {
    removable.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      const float* s = &map_.log_scales[i * 3];
      removable[i] = map_.opacity_logits[i] < min_logit || std::max({s[0], s[1], s[2]}) > max_log_scale;
    }
  }
  Pruned removed;
  for (std::size_t i = 0; i < n; ++i) {
    const bool ghost = seen_through_[i] >= config_.ghost_views && seen_through_[i] > 2 * seen_on_[i];
    if (removable[i] || ghost) {
      keep[i] = 0;
      ++removed.gaussians;
      removed.ghosts += ghost;
    }
  }
  if (removed.gaussians > 0) {
    if (device_ && !host_current_) {
      device_->keep(keep);
      device_changed();
    } else {  // the host's copy stays current, the device's follows it
      remove_gaussians(map_, keep);
      if (!device_ || host_adam_current_) adam_.remove(keep);
      if (device_) device_->keep(keep);
    }
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

uint64_t Mapper::store_refinement_frame(const splat::RgbdFrame& frame, std::optional<std::size_t> frame_id) {
  if (frame_id) {
    const uint64_t key = kSweepFrames + *frame_id;
    if (sweep_frames_.count(key)) return key;
    const double mib = static_cast<double>(frame.rgb.size() + frame.depth.size() + frame.ignore.size()) * 4 / (1 << 20);
    if (sweep_frames_mib_ + mib <= config_.sweep_device_cache_mib) {
      device_->set_target(key, frame);
      sweep_frames_.insert(key);
      sweep_frames_mib_ += mib;
      return key;
    }
  }
  device_->set_target(kRefineTarget, frame);
  return kRefineTarget;
}

void Mapper::release_sweep_frames() {
  if (device_) {
    for (const uint64_t key : sweep_frames_) device_->drop_target(key);
  }
  sweep_frames_.clear();
  sweep_frames_mib_ = 0;
}

double Mapper::refine(const splat::RgbdFrame& refinement_frame, Eigen::Isometry3d& T_cam_world,
                      PoseAdam* pose, int iterations, bool densify_first,
                      std::optional<std::size_t> frame_id, const ExposureMotion& motion,
                      std::optional<double> learning_rate_scale) {
  if (size() == 0) return 0;
  const double rate_scale = learning_rate_scale.value_or(config_.refine_learning_rate_scale);
  if (!(rate_scale > 0) || !std::isfinite(rate_scale)) {
    throw splat::Error("Mapper::refine: the learning rate scale must be finite and > 0, got " +
                       std::to_string(rate_scale));
  }
  if (motion.samples < 1 || !motion.twist.allFinite()) {
    throw splat::Error("Mapper::refine: exposure motion needs samples >= 1 and a finite twist, got " + std::to_string(motion.samples) + " samples");
  }
  Keyframe kf{refinement_frame, T_cam_world};
  kf.motion = motion;
  const uint64_t key = device_ ? store_refinement_frame(kf.frame, frame_id) : kRefineTarget;
  if (densify_first) {
    densify(kf.frame, key, kf.T_cam_world, config_.refine_seed_depth_holes, added_ > 0 ? added_ - 1 : 0);
  }
  double loss = 0;
  for (int it = 0; it < iterations; ++it)
    loss = optimize_step(kf, Step::kRefine, pose, key, rate_scale);
  T_cam_world = kf.T_cam_world;
  return loss;
}

std::vector<std::pair<std::size_t, Eigen::Isometry3d>> Mapper::keyframe_poses() const {
  std::vector<std::pair<std::size_t, Eigen::Isometry3d>> poses;
  for (const Keyframe& kf : keyframes_) poses.emplace_back(kf.number, kf.T_cam_world);
  return poses;
}

MapperState Mapper::state() const {
  pull_from_device(true);
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
  if (s.map.sh_degree != config_.seed.sh_degree) {
    throw splat::Error("Mapper::restore: a map of SH degree " + std::to_string(s.map.sh_degree) + ", this mapper seeds degree " +
                       std::to_string(config_.seed.sh_degree));
  }
  if (!s.adam.steps.empty() && (s.adam.m.sh_degree != s.map.sh_degree || s.adam.v.sh_degree != s.map.sh_degree)) {
    throw splat::Error("Mapper::restore: optimizer moments of SH degree " + std::to_string(s.adam.m.sh_degree) + " and " +
                       std::to_string(s.adam.v.sh_degree) + " for a map of degree " + std::to_string(s.map.sh_degree));
  }
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
  if (adam_.size() != map_.size()) adam_.append(map_.size(), map_.sh_degree);  // never stepped: zero moments
  if (device_) {
    for (const Keyframe& kf : keyframes_) device_->drop_target(kf.number);
  }
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
  push_to_device();
  if (device_) {
    for (const Keyframe& kf : keyframes_) device_->set_target(kf.number, kf.frame);
  }
}

void Mapper::correct_keyframes(const std::vector<Eigen::Isometry3d>& world_correction) {
  if (world_correction.size() != added_) {
    throw splat::Error("Mapper::correct_keyframes: " + std::to_string(world_correction.size()) + " corrections for " +
                       std::to_string(added_) + " keyframes");
  }
  pull_from_device(true);
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
  push_to_device();
}

MappingStats Mapper::add_keyframe(const splat::RgbdFrame& frame, const Eigen::Isometry3d& T_cam_world) {
  MappingStats stats;
  splat::RgbdFrame mapped = splat::downsample(frame, config_.resolution_factor);
  if (device_) device_->set_target(added_, mapped);  // first: a frame it refuses adds no keyframe
  keyframes_.push_back({std::move(mapped), T_cam_world, added_++});
  Keyframe& newest = keyframes_.back();
  if (device_) {
    count_free_space(device_->free_space_test(newest.number, splat::posed(newest.frame.camera, newest.T_cam_world), 0,
                                              free_space_test()), 0);
  } else {
    observe_free_space(newest.frame, newest.T_cam_world);
  }
  stats.added = densify(newest.frame, newest.number, newest.T_cam_world, false, newest.number);
  const std::vector<Keyframe*> window = window_for(newest);
  stats.window = window.size();
  // Half the steps on the new keyframe, the rest spread over the window at random.
  std::uniform_int_distribution<std::size_t> pick(0, window.size() - 1);
  for (int it = 0; it < config_.iterations && size() > 0; ++it) {
    Keyframe& kf = it % 2 == 0 ? newest : *window[pick(rng_)];
    stats.final_loss = optimize_step(kf, Step::kWindow, nullptr, kf.number, 1.0);
    ++stats.iterations;
  }
  const Pruned pruned = prune();
  stats.pruned = pruned.gaussians;
  stats.ghosts = pruned.ghosts;
  // Bounded memory: drop the oldest stored keyframe (the recent ones are the covisible ones
  // in a continuous sequence).
  if (keyframes_.size() > config_.max_keyframes) {
    if (device_) device_->drop_target(keyframes_.front().number);
    keyframes_.pop_front();
  }
  return stats;
}

}  // namespace mapping
