// When the odometry calls a converged alignment lost: its depth residuals against the recent ones.
#include <vector>

#include <gtest/gtest.h>

#include "datasets/dataset.h"
#include "datasets/synthetic_sequence.h"
#include "evaluation/trajectory_errors.h"
#include "slam/frame_tracker.h"
#include "slam/slam_config.h"
#include "splat/rasterizer.h"
#include "support/synthetic_dataset.h"
#include "support/temp_dir.h"

namespace {

const double kFactor = app::SlamConfig{}.lost_residual_factor;

TEST(ResidualRatio, AgainstTheMedianOfTheRecentFrames) {
  const std::vector<double> recent = {1.5, 2.0, 2.5, 1.8, 2.2, 40.0};  // one outlier does not move it
  EXPECT_DOUBLE_EQ(app::residual_ratio(4.4, recent), 2.0);
  EXPECT_GT(app::residual_ratio(1194 * 2.2, recent), kFactor) << "a kidnapped camera's wrong pose is lost";
  EXPECT_EQ(app::residual_ratio(1000, {2, 2, 2, 2}), 0) << "fewer than five frames say nothing";
}

// Noise-free depth (a generated sequence) gives residual spreads far below the sensor noise; a
// surface coming into view then raised the spread 24x at a correct pose (generated loop_blur,
// frame 180), and the frame was called lost. Under the sensor noise nothing is lost.
TEST(ResidualRatio, NeverCountsResidualsUnderTheSensorNoiseAsLost) {
  const std::vector<double> noise_free = {0.01, 0.012, 0.011, 0.009, 0.01};
  EXPECT_LT(app::residual_ratio(0.24, noise_free), kFactor);
  EXPECT_LT(app::residual_ratio(0.99, noise_free), 1.0);
  EXPECT_GT(app::residual_ratio(1194 * 0.01 + kFactor, noise_free), kFactor) << "far above the noise is still lost";
}

// The odometry's ATE (cm) over `dataset`, keyframes as the tracker chooses them, no map.
double odometry_ate(const app::Dataset& dataset, const app::SlamConfig& config) {
  auto rasterizer = splat::make_cpu_rasterizer({1});
  app::FrameTracker tracker(*rasterizer, config);
  const splat::Gaussians no_map;
  std::vector<Eigen::Isometry3d> keyframes;
  std::vector<app::StampedPose> estimate, truth;
  for (std::size_t i = 0; i < dataset.entries.size(); ++i) {
    const splat::RgbdFrame frame = dataset.load(i);
    app::FrameRecord record;
    if (i == 0) {
      tracker.start(frame);
      keyframes.push_back(Eigen::Isometry3d::Identity());
    } else {
      record = tracker.track(no_map, frame, [&](std::size_t k) { return keyframes[k]; });
      EXPECT_TRUE(record.tracked) << "frame " << i << ": " << record.reason;
      if (tracker.wants_keyframe(record)) {
        tracker.keyframe_added(record, keyframes.size());
        keyframes.push_back(record.T_world_cam);
      }
    }
    estimate.push_back({frame.timestamp, record.T_world_cam});
    truth.push_back({frame.timestamp, *dataset.entries[i].T_world_cam_truth});
  }
  return 100 * app::evaluate_trajectory(estimate, truth).ate_rmse;
}

// A rolling-shutter camera turning fast (the generator's rows read over 28 ms, 2.2 rad/s peaks):
// each frame is skewed by up to 16 px, and odometry that takes it for a global shutter drifts;
// told the readout, it moves every point to its frame's middle row with the keyframe's and the
// frame's own velocities, and drifts several times less. Told a readout the camera does not have,
// a global-shutter camera's odometry drifts as much.
TEST(RollingShutter, OdometryToldTheReadoutFollowsTheCamera) {
  gslam::test::TempDir dir;
  app::SyntheticOptions o = app::SyntheticOptions::hard_motion();
  o.frames = 60;
  o.rolling_shutter = 0.028;
  const app::Dataset rolling = gslam::test::synthetic_dataset(dir / "rolling", o);
  o.rolling_shutter = 0;
  const app::Dataset global = gslam::test::synthetic_dataset(dir / "global", o);
  app::SlamConfig config, told;
  told.odometry.rolling_shutter = 0.028;
  const double as_global = odometry_ate(rolling, config), corrected = odometry_ate(rolling, told);
  const double global_ate = odometry_ate(global, config), wrongly = odometry_ate(global, told);
  std::printf("rolling shutter: ATE %.2f cm taken as global, %.2f cm corrected; global shutter %.2f cm, "
              "%.2f cm corrected for a readout it does not have\n",
              as_global, corrected, global_ate, wrongly);
  EXPECT_LT(corrected, as_global / 3);
  EXPECT_LT(corrected, 3 * global_ate + 0.1);
  EXPECT_GT(wrongly, 3 * global_ate);
}

}  // namespace
