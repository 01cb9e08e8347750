#pragma once
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "mapping/mapper.h"
#include "splat/rasterizer.h"
#include "splat/rgbd_frame.h"
#include "tracking/tracker.h"

namespace app {

struct SlamConfig {
  tracking::TrackingConfig tracking;
  mapping::MapperConfig mapping;
  // A frame becomes a keyframe every `keyframe_every` frames, or earlier after this much motion
  // since the last keyframe.
  int keyframe_every = 5;
  double keyframe_translation = 0.05;  // metres
  double keyframe_rotation_deg = 5.0;
  // After the last frame (offline runs): sweep the keyframes (or every tracked frame, with
  // refine_all_frames), reloaded from the dataset, this many times in shuffled order with
  // `refine_iterations` map steps per visit.
  int refine_passes = 0;  // set by the constructor, like the other defaults tuned on teddy
  int refine_iterations = 0;
  // Sweep every tracked frame instead of the keyframes alone: more viewpoints for the same
  // number of steps.
  bool refine_all_frames = false;
  // The first this many passes also densify each visited frame (Mapper::refine), covering
  // what no keyframe saw.
  int refine_densify_passes = 0;
  // The sweep keeps visited frames (at the refinement resolution) in memory up to this many MiB
  // and reloads the rest on every pass. Teddy's 193 frames take 237 MiB at 320x240; reloading
  // them cost 9 ms per visit.
  double refine_cache_mib = 512;
  // Then re-track every refined frame but the first against the final map, from its current
  // pose, with this many Levenberg-Marquardt iterations at the finest tracking level (0: off).
  int relocalize_iterations = 0;
  SlamConfig();
};

struct FrameRecord {
  double timestamp = 0;
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
  bool tracked = true;       // false: tracking failed even after the retry
  bool retried = false;
  std::string reason;        // why tracking failed
  bool keyframe = false;
  int renders = 0;
  double tracking_ms = 0, mapping_ms = 0;
  std::size_t gaussians = 0;
};

// The tracking half of SLAM: each new frame tracked against a map from the constant-velocity
// guess (the last motion scaled to the time since the last frame, so dropped frames are bridged), retried once from the last pose with the first-order warm-up on
// failure. Failed frames keep their best pose and are reported. Shared by the offline
// SlamSystem and the live pipeline, whose map comes from another thread.
class FrameTracker {
 public:
  FrameTracker(splat::Rasterizer& rasterizer, const SlamConfig& config);
  // The first frame (at `timestamp`) defines the world frame.
  void start(double timestamp);
  // Fills timestamp, pose, tracked, retried, reason, renders and tracking_ms.
  FrameRecord track(const splat::Gaussians& map, const splat::RgbdFrame& frame);
  // Whether a tracked frame at this pose should become a keyframe; keyframe_added() resets.
  bool wants_keyframe(const FrameRecord& record) const;
  void keyframe_added(const Eigen::Isometry3d& T_world_cam);
  bool started() const { return !last_poses_.empty(); }

 private:
  splat::Rasterizer& rasterizer_;
  SlamConfig config_;
  std::vector<Eigen::Isometry3d> last_poses_;  // the last two camera-to-world poses
  std::vector<double> last_times_;             // and their timestamps
  Eigen::Isometry3d last_keyframe_ = Eigen::Isometry3d::Identity();
  int since_keyframe_ = 0;
};

// RGB-D SLAM on one sequence, frame by frame: track against the map, then on keyframes extend
// and refine the map. Frames whose tracking failed never become keyframes, so a bad pose does
// not corrupt the map.
class SlamSystem {
 public:
  SlamSystem(splat::Rasterizer& rasterizer, const SlamConfig& config);
  FrameRecord process(const splat::RgbdFrame& frame);
  const splat::Gaussians& map() const { return mapper_.map(); }
  const mapping::Vignetting& vignetting() const { return mapper_.vignetting(); }
  std::size_t keyframes_added() const { return keyframes_; }
  // The frames refine_map visits, by index into `records`.
  std::vector<std::size_t> refine_frames(const std::vector<FrameRecord>& records) const;
  // The final sweep (SlamConfig::refine_passes) over the keyframes, or all tracked frames
  // (refine_all_frames), among `records` (as process() returned them, one per frame), each
  // loaded with load(frame index) and kept while refine_cache_mib allows; a shuffled order, the
  // same on every run. Visited frames but the first (the world frame) move with the map where
  // MapperConfig::refine_pose_rate_scale > 0. Then prunes. Calls visited(done, total) after
  // each visit.
  struct Refinement {
    std::size_t pruned = 0;
    std::vector<Eigen::Isometry3d> T_world_cam;  // every record's pose after the sweep
  };
  Refinement refine_map(const std::vector<FrameRecord>& records,
                        const std::function<splat::RgbdFrame(std::size_t)>& load,
                        const std::function<void(std::size_t, std::size_t)>& visited = {});
  // Camera-to-world poses of every frame processed so far. Mapping may move keyframes
  // (MapperConfig::pose_learning_rate); each frame follows the keyframe it was tracked after.
  std::vector<Eigen::Isometry3d> trajectory() const;

 private:
  // A frame's pose relative to the keyframe before it (or itself).
  struct Anchor {
    std::size_t keyframe;
    Eigen::Isometry3d T_keyframe_cam;
  };
  FrameRecord track_and_map(const splat::RgbdFrame& frame);
  void sync_keyframe_poses();

  SlamConfig config_;
  splat::Rasterizer& rasterizer_;
  FrameTracker tracker_;
  mapping::Mapper mapper_;
  std::size_t keyframes_ = 0;
  std::vector<Eigen::Isometry3d> keyframe_world_;  // T_world_cam per keyframe number
  std::vector<Anchor> anchors_;                    // per frame
};

}  // namespace app
