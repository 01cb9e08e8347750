#include "slam/frame_tracker.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "slam/elapsed.h"
#include "splat/se3.h"
#include "tracking/tracker.h"

namespace app {

FrameTracker::FrameTracker(splat::Rasterizer& rasterizer, const SlamConfig& config)
    : rasterizer_(rasterizer), config_(config) {}

void FrameTracker::start(double timestamp) {
  last_poses_ = {Eigen::Isometry3d::Identity()};
  last_times_ = {timestamp};
  last_keyframe_ = Eigen::Isometry3d::Identity();
  since_keyframe_ = 0;
}

FrameRecord FrameTracker::track(const splat::GaussiansView& map, const splat::RgbdFrame& frame) {
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
    retry.warmup_iterations = config_.retry_warmup_iterations;
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

}  // namespace app
