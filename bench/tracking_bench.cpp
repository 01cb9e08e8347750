// Tracking cost per frame on the real sequences in ../shared/data, one thread: the SLAM system's
// frame tracker (odometry against the reference keyframe, moving regions, recovery), keyframes
// as it chooses them, no mapping. Prints a table: median and p95 time per frame, the tracking
// alone's ATE, failures, frames where moving regions were found, and the median of the depth
// residuals' spread (units of the sensor's noise: how well the camera model fits the frames).
//   tracking_bench [--config slam.json] [--frames N] [--dataset DIR] [--per-frame]
// --dataset tracks that sequence instead (any layout gslam reads, e.g. a generated one);
// --per-frame also prints a line per frame: its motion's error against the ground truth's,
// keyframe, lost, moving share and residual spread (where a drift starts).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "evaluation/trajectory_errors.h"
#include "datasets/dataset.h"
#include "io/slam_config_io.h"
#include "slam/frame_tracker.h"
#include "splat/rasterizer.h"

namespace {

struct Sequence {
  const char* name;
  const char* path;  // under ../shared/data
};

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))];
}

}  // namespace

int main(int argc, char** argv) {
  std::filesystem::path config_path;
  std::filesystem::path dataset_path;
  int max_frames = 0;
  bool per_frame = false;
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--per-frame")) {
      per_frame = true;
      continue;
    }
    if (i + 1 >= argc) break;
    if (!std::strcmp(argv[i], "--config")) config_path = argv[++i];
    else if (!std::strcmp(argv[i], "--frames")) max_frames = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--dataset")) dataset_path = argv[++i];
  }
  const app::SlamConfig config = app::load_slam_config(config_path);
  const std::filesystem::path root = dataset_path.empty() ? GSLAM_SHARED_DATA_DIR : dataset_path.parent_path();
  std::vector<Sequence> sequences = {
      {"TUM fr3/teddy", "tum_rgbd_fr3_teddy_first200/rgbd_dataset_freiburg3_teddy"},
      {"7-Scenes redkitchen", "sevenscenes_redkitchen_first200"},
  };
  const std::string dataset_name = dataset_path.filename().string();
  if (!dataset_path.empty()) sequences = {{dataset_name.c_str(), dataset_name.c_str()}};
  std::printf("| sequence | frames | median ms | p95 ms | odometry ATE | failures | frames with moving regions | median depth residual spread |\n");
  std::printf("|---|---|---|---|---|---|---|---|\n");
  for (const Sequence& s : sequences) {
    if (!std::filesystem::exists(root / s.path)) {
      std::printf("| %s | skipped: %s not found | | | | | | |\n", s.name, (root / s.path).c_str());
      continue;
    }
    app::DatasetOptions options;
    options.max_frames = max_frames;
    const app::Dataset dataset = app::open_dataset(root / s.path, options);
    std::vector<splat::RgbdFrame> frames;  // loaded first: reading PNGs is not tracking
    for (std::size_t i = 0; i < dataset.entries.size(); ++i) frames.push_back(dataset.load(i));
    std::vector<double> total_ms, spreads;
    std::vector<app::StampedPose> estimate, truth;
    // The SLAM system's own tracker (app/slam/frame_tracker.h), keyframes as it chooses them;
    // the map is never rendered by the odometry front end.
    auto rasterizer = splat::make_cpu_rasterizer();
    app::FrameTracker tracker(*rasterizer, config);
    const splat::Gaussians no_map;
    std::vector<Eigen::Isometry3d> keyframes;
    int failures = 0;
    std::size_t moving_frames = 0;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      const auto start = std::chrono::steady_clock::now();
      app::FrameRecord record;
      if (i == 0) {
        tracker.start(frames[i]);
        keyframes.push_back(Eigen::Isometry3d::Identity());
      } else {
        record = tracker.track(no_map, frames[i], [&](std::size_t k) { return keyframes[k]; });
        if (tracker.wants_keyframe(record)) {
          tracker.keyframe_added(record, keyframes.size());
          keyframes.push_back(record.T_world_cam);
        }
      }
      total_ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count());
      failures += record.tracked ? 0 : 1;
      moving_frames += record.moving_share > 0;
      if (record.tracked && i > 0) spreads.push_back(record.residual_spread);
      estimate.push_back({frames[i].timestamp, record.T_world_cam});
      const auto& truth_pose = dataset.entries[i].T_world_cam_truth;
      if (truth_pose) truth.push_back({frames[i].timestamp, *truth_pose});
      if (per_frame && i > 0 && truth_pose && dataset.entries[i - 1].T_world_cam_truth) {
        // This frame's motion from the last, against the ground truth's (world frames cancel).
        const Eigen::Isometry3d moved = estimate[i - 1].T_world_cam.inverse() * record.T_world_cam;
        const Eigen::Isometry3d truly = dataset.entries[i - 1].T_world_cam_truth->inverse() * *truth_pose;
        const Eigen::Isometry3d off = truly.inverse() * moved;
        std::printf("frame %zu: motion off by %.2f cm %.2f deg%s%s, moving %.0f%%, spread %.2f%s%s\n", i,
                    off.translation().norm() * 100, Eigen::AngleAxisd(off.linear()).angle() * 180 / M_PI,
                    record.keyframe || tracker.wants_keyframe(record) ? ", keyframe" : "",
                    record.tracked ? "" : ", lost", 100 * record.moving_share, record.residual_spread,
                    record.reason.empty() ? "" : ": ", record.reason.c_str());
      }
    }
    const app::TrajectoryErrors e = app::evaluate_trajectory(estimate, truth);
    std::printf("| %s | %zu | %.1f | %.1f | %.2f cm | %d | %zu | %.3f |\n", s.name, frames.size(),
                percentile(total_ms, 0.5), percentile(total_ms, 0.95), e.ate_rmse * 100, failures, moving_frames,
                percentile(spreads, 0.5));
  }
  return 0;
}
