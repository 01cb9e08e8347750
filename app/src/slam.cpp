#include "app/slam.h"

#include <chrono>
#include <cmath>

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
  mapping.resolution_factor = 2;
  mapping.iterations = 45;  // teddy, first 100 frames: 30 -> 45 took ATE 1.31 -> 1.11 cm, 1.44 -> 1.21 fps
  mapping.seed.scale_factor = 0.6;
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
    : tracker_(rasterizer, config), mapper_(rasterizer, config.mapping) {}

FrameRecord SlamSystem::process(const splat::RgbdFrame& frame) {
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
