// The exposure measured from the frames (tracking/exposure_estimate.h): against sequences the
// project's generator blurs over a known exposure, and its fall-backs to the prior.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "datasets/synthetic_sequence.h"
#include "splat/error.h"
#include "support/synthetic_dataset.h"
#include "support/temp_dir.h"
#include "tracking/exposure_estimate.h"

namespace {

// A frame of vertical and horizontal stripes, blurred along x over `blur` pixels.
splat::RgbdFrame stripes(float blur) {
  splat::RgbdFrame f;
  f.camera.fx = f.camera.fy = 200;
  f.camera.width = 160, f.camera.height = 120;
  f.camera.cx = 80, f.camera.cy = 60;
  f.rgb.resize(160 * 120 * 3);
  f.depth.assign(160 * 120, 1.f);
  auto pattern = [](double x, double y) { return 0.5 + 0.25 * std::sin(x / 3) + 0.25 * std::sin(y / 3); };
  const int samples = 16;
  for (int y = 0; y < 120; ++y) {
    for (int x = 0; x < 160; ++x) {
      double v = 0;
      for (int k = 0; k < samples; ++k) v += pattern(x + blur * ((k + 0.5) / samples - 0.5), y);
      for (int c = 0; c < 3; ++c) f.rgb[(static_cast<std::size_t>(y) * 160 + x) * 3 + c] = static_cast<float>(v / samples);
    }
  }
  return f;
}

TEST(ExposureEstimate, SharpnessFallsAlongTheBlurAndNotAcrossIt) {
  tracking::OdometryConfig config;
  config.finest_width = 160;
  const tracking::OdometryFrame sharp(stripes(0), config), blurred(stripes(12), config);
  const double still = tracking::directional_sharpness(sharp, {1, 0});
  EXPECT_NEAR(still, 1, 0.05) << "the same stripes both ways";
  EXPECT_LT(tracking::directional_sharpness(blurred, {1, 0}), 0.5 * still);
  EXPECT_GT(tracking::directional_sharpness(blurred, {0, 1}), 2 * still) << "across the blur is the inverse ratio";
}

// The exposure estimated from a generated sequence's frames and true angular velocities.
double estimated_exposure(const gslam::test::TempDir& dir, double exposure) {
  app::SyntheticOptions o = app::SyntheticOptions::hard_motion();
  o.frames = 90;  // three seconds: 60 frames leave too few slow ones to fit
  o.shake_peak_rate = 1.5;
  o.exposure = exposure;
  o.blur_samples = 4;
  const app::Dataset d = gslam::test::synthetic_dataset(dir / ("exposure" + std::to_string(exposure)), o);
  const tracking::OdometryConfig config;
  tracking::ExposureEstimate estimate(config);
  for (std::size_t i = 1; i < d.entries.size(); ++i) {
    const Eigen::AngleAxisd turn((d.entries[i - 1].T_world_cam_truth->inverse() * *d.entries[i].T_world_cam_truth).linear());
    estimate.observe(tracking::OdometryFrame(d.load(i), config), turn.axis() * turn.angle() * o.fps);
  }
  return estimate.exposure();
}

TEST(ExposureEstimate, MeasuresTheExposureTheFramesWereBlurredOver) {
  gslam::test::TempDir dir;
  const double short_exposure = estimated_exposure(dir, 1.0 / 120), long_exposure = estimated_exposure(dir, 1.0 / 40);
  std::printf("estimated 1/%.0f s for 1/120 s, 1/%.0f s for 1/40 s\n", 1 / short_exposure, 1 / long_exposure);
  // A coarse measurement: how fast gradients fade per pixel of blur depends on the scene's
  // texture, and fade_per_blur_px is one figure for all scenes (here 1/58 and 1/24 s). What the
  // depth weight needs is the order of magnitude, and which of two cameras blurs more.
  EXPECT_GT(long_exposure, 2 * short_exposure);
  EXPECT_GT(long_exposure, 1.0 / 40 / 2.5);
  EXPECT_LT(long_exposure, 1.0 / 40 * 2.5);
  EXPECT_LT(short_exposure, 1.0 / 120 * 2.5);
}

TEST(ExposureEstimate, KeepsThePriorUntilTheFramesSaySomething) {
  tracking::OdometryConfig config;
  config.finest_width = 160;
  tracking::ExposureEstimate estimate(config);
  const tracking::OdometryFrame frame(stripes(0), config);
  for (int i = 0; i < 100; ++i) estimate.observe(frame, Eigen::Vector3d::Zero());
  EXPECT_EQ(estimate.exposure(), config.exposure) << "a camera that never turned";
  EXPECT_EQ(estimate.samples().size(), 100u);
  // Turning at up to 0.95 rad/s: 3.2 px of nominal blur at the prior's 1/60 s.
  for (int i = 0; i < 200; ++i) estimate.observe(frame, Eigen::Vector3d(0, 0.05 * (i % 20), 0));
  EXPECT_EQ(estimate.samples().size(), static_cast<std::size_t>(config.exposure_window));
  EXPECT_LT(estimate.exposure(), config.exposure) << "as sharp turning as still: a short exposure";
  config.estimate_exposure = false;
  EXPECT_EQ(estimate.exposure(), config.exposure);
}

TEST(ExposureEstimate, RestoreChecksWhatItIsGiven) {
  tracking::OdometryConfig config;
  tracking::ExposureEstimate estimate(config);
  EXPECT_THROW(estimate.restore(std::vector<std::array<double, 2>>(config.exposure_window + 1, {1, 1})), splat::Error);
  EXPECT_THROW(estimate.restore({{1, std::nan("")}}), splat::Error);
  const std::vector<std::array<double, 2>> samples = {{0.5, 1.1}, {2.0, 1.6}};
  estimate.restore(samples);
  EXPECT_EQ(estimate.samples(), samples);
}

}  // namespace
