// SlamSystem's final sweep: the map refined over the tracked frames after the last one.
#include <algorithm>
#include <cmath>
#include <optional>
#include <random>

#include "slam/frame_prefetch.h"
#include "slam/slam_system.h"
#include "tracking/tracker.h"

namespace app {

// The blur model's views are this many sweep pixels apart, so that their mean is a smooth streak
// (the setting measured in docs/tuning.md; a frame under 1.5 px of blur renders once).
constexpr double kBlurPxPerView = 1;

std::vector<std::size_t> SlamSystem::refine_frames() const {
  std::lock_guard lock(mutex_);
  std::vector<std::size_t> frames;
  for (std::size_t i = 0; i < frames_.size(); ++i) {
    if (frames_[i].is_keyframe || (config_.refine_all_frames && frames_[i].tracked && !frames_[i].held_out)) {
      frames.push_back(i);
    }
  }
  return frames;
}

std::vector<mapping::ExposureMotion> SlamSystem::exposure_motions(
    const std::vector<std::size_t>& frames, const std::vector<Eigen::Isometry3d>& T_world_cam,
    const std::function<const splat::RgbdFrame&(std::size_t)>& frame_at) const {
  std::vector<mapping::ExposureMotion> motion(T_world_cam.size());
  const double exposure = config_.odometry.exposure;  // the nominal exposure: see docs/tuning.md
  if (config_.refine_blur_samples <= 1 || frames.size() < 2 || !(exposure > 0)) return motion;
  const double fx = frame_at(frames.front()).camera.fx;  // at the sweep's resolution
  std::vector<double> times(frames.size());
  for (std::size_t k = 0; k < frames.size(); ++k) times[k] = frame_at(frames[k]).timestamp;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    // The motion between the neighbouring swept frames, scaled to the exposure.
    const std::size_t a = k > 0 ? k - 1 : k, b = k + 1 < frames.size() ? k + 1 : k;
    const double dt = times[b] - times[a];
    if (!(dt > 0)) continue;
    const splat::Vector6d twist = splat::se3_log(T_world_cam[frames[a]].inverse() * T_world_cam[frames[b]]) * (exposure / dt);
    const double blur_px = fx * twist.tail<3>().norm();
    if (!std::isfinite(blur_px)) continue;
    motion[frames[k]] = {twist, static_cast<int>(std::clamp(std::round(blur_px / kBlurPxPerView), 1.0, double(config_.refine_blur_samples)))};
  }
  return motion;
}

SlamSystem::Refinement SlamSystem::refine_map(const std::function<splat::RgbdFrame(std::size_t)>& load,
                                              const std::function<void(std::size_t, std::size_t)>& visited,
                                              const std::function<bool()>& stop) {
  finish();  // the mapper is this thread's from here on
  Refinement result;
  const std::vector<std::size_t> frames = refine_frames();
  result.frames = frames.size();
  if (config_.refine_passes <= 0 || frames.empty()) return result;
  std::vector<Eigen::Isometry3d> T_world_cam = trajectory();
  std::size_t world_frame = 0;  // the first keyframe's frame: it stays where it defines the world
  {
    std::lock_guard lock(mutex_);
    while (world_frame < frames_.size() && !frames_[world_frame].is_keyframe) ++world_frame;
  }
  std::vector<mapping::PoseAdam> poses(T_world_cam.size());
  std::vector<std::size_t> order = frames;
  std::mt19937 rng(1);
  // Frames kept in memory (bounded by refine_cache_mib), the others reloaded on each visit.
  std::vector<std::optional<splat::RgbdFrame>> cache(T_world_cam.size());
  splat::RgbdFrame uncached;
  double cached_mib = 0;
  FramePrefetch prefetch(load, frames);  // the first visits (carving) go through them in turn
  auto frame_at = [&](std::size_t i) -> const splat::RgbdFrame& {
    if (cache[i]) return *cache[i];
    splat::RgbdFrame loaded = prefetch.take(i);
    {
      std::lock_guard lock(mutex_);
      // Its depth moved as process() moved it, and moving objects left out of the map.
      if (!frames_[i].T_colour_depth.isApprox(Eigen::Isometry3d::Identity())) {
        splat::move_depth_to_colour_time(loaded, frames_[i].T_colour_depth);
      }
      frames_[i].moving.apply(loaded);
    }
    splat::RgbdFrame f = mapper_.refinement_frame(loaded);
    const double mib = static_cast<double>((f.rgb.size() + f.depth.size()) * sizeof(float)) / (1 << 20);
    if (cached_mib + mib > config_.refine_cache_mib) return uncached = std::move(f);
    cached_mib += mib;
    return *(cache[i] = std::move(f));
  };
  // map() follows the sweep's Gaussian count: a snapshot is published after each visit that
  // changed it (the densifying passes only; a copy per visit of the others would cost more than
  // it tells), so a progress line reading map()->size() sees Gaussians being added.
  std::size_t published = mapper_.size();
  auto publish = [&] {
    auto snapshot = std::make_shared<const splat::Gaussians>(mapper_.map());
    std::lock_guard lock(mutex_);
    map_ = std::move(snapshot);
  };
  // Every frame's view of each Gaussian, before the sweep: ghosts (what moving objects left) go
  // now, and the densifying passes seed what they covered. What those passes seed is tested the
  // same way after them: a person who stood still joined the scene, and the frames where it walks
  // off again show it where tracking does not find it moving.
  auto prune_map = [&](bool oversized) {
    const mapping::Mapper::Pruned pruned = mapper_.prune(oversized);
    result.pruned += pruned.gaussians;
    result.ghosts += pruned.ghosts;
  };
  auto carve = [&](std::size_t first) {
    for (const std::size_t i : frames) mapper_.observe_free_space(frame_at(i), T_world_cam[i].inverse(), first);
    prune_map(true);
  };
  carve(0);
  const std::vector<mapping::ExposureMotion> motion = exposure_motions(frames, T_world_cam, frame_at);
  result.blurred = static_cast<std::size_t>(std::count_if(frames.begin(), frames.end(), [&](std::size_t i) { return motion[i].samples > 1; }));
  const std::size_t seeded_from = mapper_.size();
  const SlamConfig::SweepVisits visits = config_.sweep_visits(frames.size());
  // After the densifying passes the frames are visited in shuffled rounds, so none is visited
  // twice before every one was once (also where refine_max_visits ends a round early).
  std::size_t next = order.size();  // the current round's next frame; a new round at the end
  for (std::size_t v = 0; v < visits.total; ++v) {
    if (stop && stop()) {
      result.stopped = true;
      break;
    }
    if (v == visits.densifying && v > 0) carve(seeded_from);
    if (next == order.size()) {
      // The oversized go as the last round begins, so that its visits fill where they were; after
      // the last visit only the transparent do (docs/tuning.md).
      if (v > visits.densifying && visits.total - v <= order.size()) prune_map(true);
      std::shuffle(order.begin(), order.end(), rng), next = 0;
    }
    const std::size_t i = order[next++];
    Eigen::Isometry3d T_cam_world = T_world_cam[i].inverse();
    mapping::PoseAdam* pose = i == world_frame ? nullptr : &poses[i];
    if (v >= visits.densifying && v < visits.densifying + visits.coarse) {
      // Not the sweep cache's frame (no frame_id): a smaller one, made anew on each visit.
      mapper_.refine(splat::downsample(frame_at(i), 2), T_cam_world, pose,
                     config_.refine_iterations, false, std::nullopt, motion[i],
                     config_.refine_coarse_learning_rate_scale);
    } else {
      mapper_.refine(frame_at(i), T_cam_world, pose, config_.refine_iterations,
                     v < visits.densifying, i, motion[i]);
    }
    T_world_cam[i] = T_cam_world.inverse();
    if (mapper_.size() != published) publish(), published = mapper_.size();
    if (visited) visited(++result.visits, visits.total);
  }
  prune_map(false);  // no visit is left to fill where an oversized one was
  mapper_.release_sweep_frames();
  if (config_.relocalize_iterations > 0) {
    tracking::TrackingConfig t = config_.tracking;
    t.pyramid = {t.pyramid.back()};
    t.iterations = {config_.relocalize_iterations};
    t.warmup_iterations = 0;
    for (const std::size_t i : frames) {
      if (i == world_frame) continue;
      const tracking::TrackingResult r =
          tracking::track_frame(tracking_rasterizer_, mapper_.map(), load(i), T_world_cam[i].inverse(), t);
      if (r.converged) T_world_cam[i] = r.T_cam_world.inverse();
    }
  }
  auto snapshot = std::make_shared<const splat::Gaussians>(mapper_.map());
  std::lock_guard lock(mutex_);
  map_ = std::move(snapshot);  // with the poses below, under one lock
  totals_.ghosts_pruned += result.ghosts;
  // The refined frames keep their keyframe, at the pose the sweep gave them.
  for (const std::size_t i : frames) {
    if (frames_[i].keyframe != kNoKeyframe) frames_[i].T_keyframe_cam = keyframe_world_[frames_[i].keyframe].inverse() * T_world_cam[i];
  }
  return result;
}

}  // namespace app
