// When the odometry calls a converged alignment lost: its depth residuals against the recent ones.
#include <vector>

#include <gtest/gtest.h>

#include "slam/frame_tracker.h"
#include "slam/slam_config.h"

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

}  // namespace
