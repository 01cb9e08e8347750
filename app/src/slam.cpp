#include "app/slam.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <optional>
#include <random>

#include "splat/se3.h"

namespace app {
namespace {
double ms_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}
}  // namespace

SlamConfig::SlamConfig() {
  // Teddy, all 193 frames: {2} -> {4, 2} took ATE 3.45 -> 3.08 cm at the same tracking time;
  // on every third frame (wider motion, as a live run that drops frames sees) 10.8 -> 4.0 cm.
  tracking.pyramid = {4, 2};
  tracking.iterations = {10, 10};
  // Levels end once a step moves less than 0.3 mm and 0.3 mrad. Teddy, 193 frames (tracking per
  // frame / ATE / PSNR): 0.01 mm and 0.01 mrad 308 ms / 0.95 cm / 24.12 dB; 0.1 261 ms / 0.95 /
  // 24.34; 0.3 215 ms / 0.95 / 24.18. The time saved pays for more refinement passes.
  tracking.min_step_translation = 3e-4;
  tracking.min_step_rotation = 3e-4;
  mapping.resolution_factor = 2;
  mapping.iterations = 45;  // teddy, first 100 frames: 30 -> 45 took ATE 1.31 -> 1.11 cm, 1.44 -> 1.21 fps
  mapping.seed.scale_factor = 0.6;
  // Keyframe poses move with the map (ATE, teddy 193 frames / synthetic room 30 frames):
  // fixed 3.08 / 0.39 cm; rotation steps of 0, 2e-5 and 5e-5 rad with 2e-4 m translation
  // steps 0.93 / 0.78, 1.03 / 0.48 and 1.24 / 0.31 cm. The last improves both; teddy's PSNR
  // goes 22.4 -> 22.1 dB. Comparing the alpha-weighted depth everywhere in the window steps
  // too (depth_alpha_threshold 1) gave teddy 1.29 cm but synthetic 0.54 cm.
  mapping.pose_learning_rate = 2e-4;
  mapping.pose_rotation_learning_rate = 5e-5;
  // Teddy, first 100 frames, keyframes alone: PSNR 20.3 -> 24.0 dB (SSIM 0.78 -> 0.85) for 14 s;
  // 8 passes gave 24.1 dB and refining at full resolution 24.05 dB, each for 2.5x the time.
  // All 193 frames, one build (PSNR / SSIM): the keyframes, 3 passes of 5 steps: 21.51 dB /
  // 0.810. Every tracked frame, one step per visit: 3 passes 22.09 / 0.823 (the same number of
  // steps); 5 passes 21.12, and 3 passes of 2 steps 20.74 (more steps at full rate degrade);
  // at 0.3x the learning rates 3 passes 21.94, 6 passes 22.39; at 0.5x, 4 passes 22.45 / 0.826.
  // Later, with the refinement's depth weight at 0.1 and the vignetting learned (below), more
  // passes help again: teddy, 4 -> 6 passes 23.29 -> 23.69 dB without vignetting; with it 6 -> 8
  // passes 24.12 -> 24.23 dB (and 24.34 -> 24.46 dB with coarser tracking stops); 8 -> 12
  // passes 24.21 -> 24.49 dB, ATE 0.90 -> 0.84 cm, for 1.43 -> 1.20 frames/s overall.
  refine_passes = 12;
  refine_iterations = 1;
  refine_all_frames = true;
  mapping.refine_learning_rate_scale = 0.5;
  // The refined frames' poses move with the map at 10x the window's pose steps. Teddy, 193
  // frames, two builds (ATE / RPE / PSNR): fixed 1.26 cm / 1.53 cm / 22.42 dB and 1.23 / 1.50 /
  // 22.64; at 10x 1.01 / 1.27 / 22.40 and 0.98 / 1.24 / 22.64. 1x moved little (1.22 cm); 30x
  // gave 0.98 cm but 21.80 dB.
  mapping.refine_pose_rate_scale = 10;
  // The refinement traded colour for depth: on teddy 16 passes at 0.3x rendered worse than 4 at
  // 0.5x (21.76 against 22.64 dB) while depth L1 improved (6.30 against 6.79 cm). Its depth
  // weight at 0.1 (the mapping window keeps 1, which tracking accuracy needs: 0.2 everywhere
  // gave 23.34 dB but ATE 1.87 cm): 22.64 -> 23.29 dB, depth L1 6.8 -> 8.4 cm; at 0, 23.76 dB
  // but depth L1 30.5 cm.
  // Later still, densifying in the sweep (below) let colour win more: at 0.1 / 0.05 / 0.03 / 0
  // teddy rendered 25.35 / 25.86 / 26.24 / 27.11 dB with depth L1 8.2 / 9.6 / 11.0 / 28.9 cm.
  // Discounting depth within a z^2 noise band, or near depth edges, moved along the same curve.
  mapping.refine_depth_weight = 0.03;
  // The camera's vignetting learned in the refinement (mapping/vignetting.h): teddy 23.29 ->
  // 23.80 dB as recorded (k1 -0.04, k2 -0.62 there: corners about 22% darker than the centre).
  mapping.refine_vignetting_rate = 2e-3;
  // The sweep's first pass also densifies each frame it visits, pixels without depth included (at
  // depth filled in from their neighbours): keyframes alone left what only other frames saw
  // empty, and the depth camera's holes (a quarter of teddy's pixels: beyond its range, at depth
  // edges, the border) were never seeded. Teddy, 193 frames, depth weight 0.1: 24.49 -> 24.92 dB
  // densifying, 25.35 dB with the holes, for 5% more Gaussians (63K); a second densifying pass
  // gave 25.48 against 25.52 dB.
  refine_densify_passes = 1;
  mapping.refine_seed_depth_holes = true;
}

FrameTracker::FrameTracker(splat::Rasterizer& rasterizer, const SlamConfig& config)
    : rasterizer_(rasterizer), config_(config) {}

void FrameTracker::start(double timestamp) {
  last_poses_ = {Eigen::Isometry3d::Identity()};
  last_times_ = {timestamp};
  last_keyframe_ = Eigen::Isometry3d::Identity();
  since_keyframe_ = 0;
}

FrameRecord FrameTracker::track(const splat::Gaussians& map, const splat::RgbdFrame& frame) {
  FrameRecord record;
  record.timestamp = frame.timestamp;
  // Constant velocity: the last inter-frame motion, scaled to this frame's time step (equal
  // steps when the timestamps do not say otherwise).
  const Eigen::Isometry3d last = last_poses_.back();
  Eigen::Isometry3d guess = last;
  if (last_poses_.size() >= 2) {
    const double step = last_times_.back() - last_times_.front(), now = frame.timestamp - last_times_.back();
    const double scale = step > 0 && now > 0 ? std::min(now / step, 10.0) : 1.0;
    const Eigen::Isometry3d motion = last_poses_.front().inverse() * last;
    guess = splat::orthonormalized(last * (scale == 1.0 ? motion : splat::se3_exp(scale * splat::se3_log(motion))));
  }
  const auto start = std::chrono::steady_clock::now();
  tracking::TrackingResult result = tracking::track_frame(rasterizer_, map, frame, guess.inverse(), config_.tracking);
  record.renders = result.renders;
  if (!result.converged) {
    // Retry from the last pose with the first-order warm-up, which has a wider basin.
    tracking::TrackingConfig retry = config_.tracking;
    retry.warmup_iterations = 20;
    const tracking::TrackingResult second = tracking::track_frame(rasterizer_, map, frame, last.inverse(), retry);
    record.retried = true;
    record.renders += second.renders;
    if (second.converged || second.final_cost < result.final_cost) result = second;
  }
  record.tracking_ms = ms_since(start);
  record.tracked = result.converged;
  record.reason = result.reason;
  record.T_world_cam = result.T_cam_world.inverse();
  // A failed frame's pose is a guess: the motion model keeps the last tracked poses.
  if (record.tracked) {
    last_poses_ = {last, record.T_world_cam};
    last_times_ = {last_times_.back(), frame.timestamp};
  }
  ++since_keyframe_;
  return record;
}

bool FrameTracker::wants_keyframe(const FrameRecord& record) const {
  if (!record.tracked) return false;
  const Eigen::Isometry3d motion = last_keyframe_.inverse() * record.T_world_cam;
  const double degrees = Eigen::AngleAxisd(motion.linear()).angle() * 180 / M_PI;
  return since_keyframe_ >= config_.keyframe_every || motion.translation().norm() > config_.keyframe_translation ||
         degrees > config_.keyframe_rotation_deg;
}

void FrameTracker::keyframe_added(const Eigen::Isometry3d& T_world_cam) {
  last_keyframe_ = T_world_cam;
  since_keyframe_ = 0;
}

SlamSystem::SlamSystem(splat::Rasterizer& rasterizer, const SlamConfig& config)
    : config_(config), rasterizer_(rasterizer), tracker_(rasterizer, config), mapper_(rasterizer, config.mapping) {}

std::vector<std::size_t> SlamSystem::refine_frames(const std::vector<FrameRecord>& records) const {
  std::vector<std::size_t> frames;
  for (std::size_t i = 0; i < records.size(); ++i) {
    if (records[i].keyframe || (config_.refine_all_frames && records[i].tracked)) frames.push_back(i);
  }
  return frames;
}

SlamSystem::Refinement SlamSystem::refine_map(const std::vector<FrameRecord>& records,
                                              const std::function<splat::RgbdFrame(std::size_t)>& load,
                                              const std::function<void(std::size_t, std::size_t)>& visited) {
  Refinement result;
  for (const FrameRecord& r : records) result.T_world_cam.push_back(r.T_world_cam);
  const std::vector<std::size_t> frames = refine_frames(records);
  if (config_.refine_passes <= 0 || frames.empty()) return result;
  std::vector<mapping::PoseAdam> poses(records.size());
  std::vector<std::size_t> order = frames;
  std::mt19937 rng(1);
  const std::size_t total = frames.size() * static_cast<std::size_t>(config_.refine_passes);
  std::size_t done = 0;
  // Frames kept in memory (bounded by refine_cache_mib), the others reloaded on each visit.
  std::vector<std::optional<splat::RgbdFrame>> cache(records.size());
  splat::RgbdFrame uncached;
  double cached_mib = 0;
  auto frame_at = [&](std::size_t i) -> const splat::RgbdFrame& {
    if (cache[i]) return *cache[i];
    splat::RgbdFrame f = mapper_.refinement_frame(load(i));
    const double mib = static_cast<double>((f.rgb.size() + f.depth.size()) * sizeof(float)) / (1 << 20);
    if (cached_mib + mib > config_.refine_cache_mib) return uncached = std::move(f);
    cached_mib += mib;
    return *(cache[i] = std::move(f));
  };
  for (int pass = 0; pass < config_.refine_passes; ++pass) {
    std::shuffle(order.begin(), order.end(), rng);
    for (const std::size_t i : order) {
      Eigen::Isometry3d T_cam_world = result.T_world_cam[i].inverse();
      mapper_.refine(frame_at(i), T_cam_world, i == 0 ? nullptr : &poses[i], config_.refine_iterations,
                     pass < config_.refine_densify_passes);
      result.T_world_cam[i] = T_cam_world.inverse();
      if (visited) visited(++done, total);
    }
  }
  result.pruned = mapper_.prune();
  if (config_.relocalize_iterations > 0) {
    tracking::TrackingConfig t = config_.tracking;
    t.pyramid = {t.pyramid.back()};
    t.iterations = {config_.relocalize_iterations};
    t.warmup_iterations = 0;
    for (const std::size_t i : frames) {
      if (i == 0) continue;  // the world frame
      const tracking::TrackingResult r =
          tracking::track_frame(rasterizer_, mapper_.map(), load(i), result.T_world_cam[i].inverse(), t);
      if (r.converged) result.T_world_cam[i] = r.T_cam_world.inverse();
    }
  }
  return result;
}

void SlamSystem::sync_keyframe_poses() {
  for (const auto& [number, T_cam_world] : mapper_.keyframe_poses()) {
    if (number >= keyframe_world_.size()) keyframe_world_.resize(number + 1);
    keyframe_world_[number] = T_cam_world.inverse();
  }
}

std::vector<Eigen::Isometry3d> SlamSystem::trajectory() const {
  std::vector<Eigen::Isometry3d> poses;
  poses.reserve(anchors_.size());
  for (const Anchor& a : anchors_) poses.push_back(keyframe_world_[a.keyframe] * a.T_keyframe_cam);
  return poses;
}

FrameRecord SlamSystem::process(const splat::RgbdFrame& frame) {
  FrameRecord record = track_and_map(frame);
  const std::size_t keyframe = keyframes_ - 1;  // this frame, or the last keyframe before it
  if (record.keyframe) {
    sync_keyframe_poses();  // mapping moved keyframes, this one included
    anchors_.push_back({keyframe, Eigen::Isometry3d::Identity()});
  } else {
    anchors_.push_back({keyframe, keyframe_world_[keyframe].inverse() * record.T_world_cam});
  }
  return record;
}

FrameRecord SlamSystem::track_and_map(const splat::RgbdFrame& frame) {
  if (!tracker_.started()) {
    // The first frame defines the world frame and seeds the map.
    FrameRecord record;
    record.timestamp = frame.timestamp;
    const auto start = std::chrono::steady_clock::now();
    mapper_.add_keyframe(frame, Eigen::Isometry3d::Identity());
    record.mapping_ms = ms_since(start);
    record.keyframe = true;
    ++keyframes_;
    tracker_.start(frame.timestamp);
    record.gaussians = mapper_.map().size();
    return record;
  }
  FrameRecord record = tracker_.track(mapper_.map(), frame);
  if (tracker_.wants_keyframe(record)) {
    const auto map_start = std::chrono::steady_clock::now();
    mapper_.add_keyframe(frame, record.T_world_cam.inverse());
    record.mapping_ms = ms_since(map_start);
    record.keyframe = true;
    tracker_.keyframe_added(record.T_world_cam);
    ++keyframes_;
  }
  record.gaussians = mapper_.map().size();
  return record;
}

}  // namespace app
