// What a SLAM run writes, the same for `gslam reconstruct` and `gslam live`: DIR/trajectory.txt
// (TUM, one line per processed frame), DIR/map.ply, DIR/map.glb, DIR/keyframes/kf_NNNN.{png,exr}
// (the final map seen from each keyframe) and DIR/summary.json. Every file is written
// atomically, so an interrupted run leaves the last complete outputs.
#pragma once
#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "datasets/dataset.h"
#include "evaluation/trajectory_errors.h"
#include "slam/frame_tracker.h"
#include "slam/slam_system.h"
#include "io/trajectory.h"
#include "splat/gaussian_labels.h"
#include "splat/rasterizer.h"

namespace app {

// One line for the progress output: "loop: frame 412 -> frame 37, 88 inliers, drift 4.1 cm /
// 1.2 deg: accepted".
std::string describe(const LoopEvent& loop);

class RunOutputs {
 public:
  // Prepares `out` for this run (io/run_folder.h: refuses another run's outputs unless
  // `overwrite`, which removes them).
  RunOutputs(std::filesystem::path out, std::string input, const splat::Rasterizer& rasterizer, bool overwrite);

  // Continues the run whose state() is `state`, in the folder it was interrupted in.
  RunOutputs(std::filesystem::path out, std::string input, const splat::Rasterizer& rasterizer,
             const nlohmann::json& state);
  // What the run has recorded so far (frames, timings, extra fields, its id), for a checkpoint.
  nlohmann::json state() const;

  // Records one processed frame.
  void add(const FrameRecord& record, double loading_ms);
  // Replaces the recorded poses (one per frame added, in order) with later estimates.
  void update_poses(const std::vector<Eigen::Isometry3d>& T_world_cam);
  // What mapping did (summary.json "mapping") and every loop it verified ("loops").
  void set_mapping(const MappingTotals& totals, const std::vector<LoopEvent>& loops, bool on_device, bool overlapped);
  // Extra summary fields (live mode: dropped frames, latency percentiles).
  nlohmann::json& extra() { return extra_; }
  // The run stopped before its input ended and can continue (reconstruct --resume): finish()
  // then writes "complete": false.
  void set_resumable(bool resumable) { resumable_ = resumable; }
  // Ctrl-C: finish() leaves out the keyframe renders (a second or more a dozen keyframes), so
  // the program stops promptly; everything else is written.
  void set_stopping(bool stopping) { stopping_ = stopping; }
  // Writes trajectory.txt and summary.json (complete: false), and map.ply when `with_map`.
  void checkpoint(const splat::Gaussians& map, std::size_t keyframes, bool with_map);
  // Writes everything: trajectory, map.ply, map.glb, keyframe renders and the final summary
  // (with ATE when `truth` has poses).
  // The map's classes (fused from label images), written into map.ply by finish().
  void set_labels(splat::GaussianLabels labels) { labels_ = std::move(labels); }
  void finish(const splat::Gaussians& map, std::size_t keyframes, splat::Rasterizer& rasterizer,
              const splat::Camera& intrinsics, const std::vector<StampedPose>& truth);

  const std::vector<FrameRecord>& records() const { return records_; }
  std::size_t failures() const { return failures_; }
  double elapsed_seconds() const;

 private:
  splat::GaussianLabels labels_;
  // The summary, with the manifest of `files` (written before it).
  nlohmann::json summary(const splat::Gaussians& map, std::size_t keyframes, bool complete,
                         const std::vector<std::filesystem::path>& files) const;

  std::filesystem::path out_;
  std::string run_id_;
  std::string input_;
  const splat::Rasterizer& rasterizer_;
  std::chrono::steady_clock::time_point start_;
  double earlier_seconds_ = 0;  // a resumed run: time spent before the interruption
  std::vector<FrameRecord> records_;
  std::vector<StampedPose> trajectory_;
  double tracking_ms_ = 0, mapping_ms_ = 0, loading_ms_ = 0;
  std::size_t failures_ = 0, retries_ = 0;
  nlohmann::json extra_ = nlohmann::json::object();
  TrajectoryErrors errors_;
  bool has_errors_ = false;
  bool resumable_ = false, stopping_ = false;
};


}  // namespace app
