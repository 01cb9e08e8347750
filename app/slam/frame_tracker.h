// The tracking half of SLAM: each new frame tracked against the map from a constant-velocity
// guess, retried once on failure, and the keyframe policy.
#pragma once
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "slam/slam_config.h"
#include "splat/gaussians.h"
#include "splat/rasterizer.h"
#include "splat/rgbd_frame.h"

namespace app {

// What the system did with one frame.
struct FrameRecord {
  double timestamp = 0;
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();  // as tracked
  bool tracked = true;  // false: tracking failed even after the retry
  bool retried = false;
  std::string reason;  // why tracking failed
  bool keyframe = false;
  int renders = 0;
  double tracking_ms = 0, mapping_ms = 0;
  std::size_t gaussians = 0;  // in the map after this frame
};

// The guess is the last motion scaled to the time since the last frame (so dropped frames are
// bridged); a failure is retried from the last pose with the first-order warm-up. Failed frames
// keep their best pose and are reported, and never move the motion model.
class FrameTracker {
 public:
  FrameTracker(splat::Rasterizer& rasterizer, const SlamConfig& config);
  // The first frame (at `timestamp`) defines the world frame.
  void start(double timestamp);
  bool started() const { return !last_poses_.empty(); }
  // Fills timestamp, pose, tracked, retried, reason, renders and tracking_ms.
  FrameRecord track(const splat::GaussiansView& map, const splat::RgbdFrame& frame);
  // Whether a tracked frame at this pose should become a keyframe; keyframe_added() resets.
  bool wants_keyframe(const FrameRecord& record) const;
  void keyframe_added(const Eigen::Isometry3d& T_world_cam);

 private:
  splat::Rasterizer& rasterizer_;
  const SlamConfig& config_;
  std::vector<Eigen::Isometry3d> last_poses_;  // the last two tracked camera-to-world poses
  std::vector<double> last_times_;             // and their timestamps
  Eigen::Isometry3d last_keyframe_ = Eigen::Isometry3d::Identity();
  int since_keyframe_ = 0;
};

}  // namespace app
