// SlamSystem's final sweep: the map refined over the tracked frames after the last one.
#include <algorithm>
#include <optional>
#include <random>

#include "slam/slam_system.h"
#include "tracking/tracker.h"

namespace app {

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
  const std::size_t total = frames.size() * static_cast<std::size_t>(config_.refine_passes);
  // Frames kept in memory (bounded by refine_cache_mib), the others reloaded on each visit.
  std::vector<std::optional<splat::RgbdFrame>> cache(T_world_cam.size());
  splat::RgbdFrame uncached;
  double cached_mib = 0;
  auto frame_at = [&](std::size_t i) -> const splat::RgbdFrame& {
    if (cache[i]) return *cache[i];
    splat::RgbdFrame loaded = load(i);
    {
      std::lock_guard lock(mutex_);
      frames_[i].moving.apply(loaded);  // moving objects stay out of the map
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
  auto prune_map = [&] {
    const mapping::Mapper::Pruned pruned = mapper_.prune();
    result.pruned += pruned.gaussians;
    result.ghosts += pruned.ghosts;
  };
  auto carve = [&](std::size_t first) {
    for (const std::size_t i : frames) mapper_.observe_free_space(frame_at(i), T_world_cam[i].inverse(), first);
    prune_map();
  };
  carve(0);
  const std::size_t seeded_from = mapper_.size();
  for (int pass = 0; pass < config_.refine_passes && !result.stopped; ++pass) {
    if (pass == config_.refine_densify_passes && pass > 0) carve(seeded_from);
    std::shuffle(order.begin(), order.end(), rng);
    for (const std::size_t i : order) {
      if (stop && stop()) {
        result.stopped = true;
        break;
      }
      Eigen::Isometry3d T_cam_world = T_world_cam[i].inverse();
      mapper_.refine(frame_at(i), T_cam_world, i == world_frame ? nullptr : &poses[i], config_.refine_iterations,
                     pass < config_.refine_densify_passes, i);
      T_world_cam[i] = T_cam_world.inverse();
      if (mapper_.size() != published) publish(), published = mapper_.size();
      if (visited) visited(++result.visits, total);
    }
  }
  prune_map();
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
