// Tracking cost per frame on the real sequences in ../shared/data, one thread: the RGB-D
// odometry front end (frame preparation + alignment against the reference keyframe) driven as
// the SLAM system drives it, with a new reference every keyframe_every frames or when overlap
// drops. Prints a table: median and p95 time per frame, the odometry alone's ATE, failures.
//   tracking_bench [--config slam.json] [--frames N]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "commands/evaluation.h"
#include "datasets/dataset.h"
#include "io/slam_config_io.h"
#include "tracking/exposure_estimate.h"
#include "tracking/rgbd_odometry.h"

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
  int max_frames = 0;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--config")) config_path = argv[i + 1];
    if (!std::strcmp(argv[i], "--frames")) max_frames = std::atoi(argv[i + 1]);
  }
  const app::SlamConfig config = app::load_slam_config(config_path);
  const std::filesystem::path root = GSLAM_SHARED_DATA_DIR;
  const Sequence sequences[] = {
      {"TUM fr3/teddy", "tum_rgbd_fr3_teddy_first200/rgbd_dataset_freiburg3_teddy"},
      {"7-Scenes redkitchen", "sevenscenes_redkitchen_first200"},
  };
  std::printf("| sequence | frames | median ms | p95 ms | prepare ms (median) | odometry ATE | failures | exposure measured |\n");
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
    std::vector<double> total_ms, prepare_ms;
    std::vector<app::StampedPose> estimate, truth;
    std::shared_ptr<const tracking::OdometryFrame> reference;
    Eigen::Isometry3d T_world_ref = Eigen::Isometry3d::Identity(), T_world_cur = T_world_ref, velocity = T_world_ref;
    int since_keyframe = 0, failures = 0;
    double last_tracked_time = frames.empty() ? 0 : frames[0].timestamp;
    Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();
    double reference_rate = 0;
    tracking::ExposureEstimate exposure(config.odometry);
    for (std::size_t i = 0; i < frames.size(); ++i) {
      const auto start = std::chrono::steady_clock::now();
      auto prepared = std::make_shared<const tracking::OdometryFrame>(frames[i], config.odometry);
      const auto prepared_at = std::chrono::steady_clock::now();
      bool keyframe = !reference;
      if (reference) {
        const Eigen::Isometry3d guess = T_world_cur * velocity;
        // The weighting the SLAM system uses: from the angular rate of the last tracked step.
        tracking::OdometryConfig odometry = config.odometry;
        odometry.exposure = exposure.exposure();
        odometry.depth_weight =
            tracking::blur_aware_depth_weight(odometry, *prepared, angular_velocity.norm(), reference_rate);
        const tracking::OdometryResult r =
            tracking::align_rgbd(*reference, *prepared, guess.inverse() * T_world_ref, odometry);
        failures += r.converged ? 0 : 1;
        const Eigen::Isometry3d next = T_world_ref * r.T_cur_ref.inverse();
        if (r.converged) {
          velocity = T_world_cur.inverse() * next, T_world_cur = next;
          const double dt = frames[i].timestamp - last_tracked_time;
          const Eigen::AngleAxisd turn(velocity.linear());
          angular_velocity = dt > 0 ? Eigen::Vector3d(turn.axis() * (turn.angle() / dt)) : Eigen::Vector3d::Zero();
          last_tracked_time = frames[i].timestamp;
          exposure.observe(*prepared, angular_velocity);
        }
        keyframe = r.converged && (++since_keyframe >= config.keyframe_every || r.overlap < config.keyframe_overlap);
      }
      const auto end = std::chrono::steady_clock::now();
      if (keyframe) reference = prepared, T_world_ref = T_world_cur, since_keyframe = 0, reference_rate = angular_velocity.norm();
      total_ms.push_back(std::chrono::duration<double, std::milli>(end - start).count());
      prepare_ms.push_back(std::chrono::duration<double, std::milli>(prepared_at - start).count());
      estimate.push_back({frames[i].timestamp, T_world_cur});
      if (dataset.entries[i].T_world_cam_truth) truth.push_back({frames[i].timestamp, *dataset.entries[i].T_world_cam_truth});
    }
    const app::TrajectoryErrors e = app::evaluate_trajectory(estimate, truth);
    std::printf("| %s | %zu | %.1f | %.1f | %.1f | %.2f cm | %d | 1/%.0f s |\n", s.name, frames.size(), percentile(total_ms, 0.5),
                percentile(total_ms, 0.95), percentile(prepare_ms, 0.5), e.ate_rmse * 100, failures, 1 / exposure.exposure());
  }
  return 0;
}
