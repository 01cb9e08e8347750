// Dense RGB-D odometry (tracking/rgbd_odometry.h): accuracy on the synthetic room and on real
// teddy frames against ground truth, and failures reported for what cannot be aligned.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "datasets/dataset.h"
#include "datasets/synthetic_sequence.h"
#include "evaluation/trajectory_errors.h"
#include "splat/error.h"
#include "splat/se3.h"
#include "support/synthetic_dataset.h"
#include "support/temp_dir.h"
#include "support/test_data.h"
#include "tracking/rgbd_odometry.h"

namespace {

struct MotionError {
  double translation_m, rotation_deg;
};
MotionError motion_error(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  const Eigen::Isometry3d d = a.inverse() * b;
  return {d.translation().norm(), Eigen::AngleAxisd(d.linear()).angle() * 180 / M_PI};
}

// Truth T_cur_ref of two dataset frames.
Eigen::Isometry3d true_motion(const app::Dataset& d, std::size_t ref, std::size_t cur) {
  return d.entries[cur].T_world_cam_truth->inverse() * *d.entries[ref].T_world_cam_truth;
}

// The first `frames` frames of a generated sequence of `path_frames` (0: `frames`).
app::Dataset synthetic(const gslam::test::TempDir& dir, int frames, int path_frames = 0) {
  app::SyntheticOptions o;
  o.frames = frames;
  o.path_frames = path_frames;
  return gslam::test::synthetic_dataset(dir / "seq", o);
}

TEST(RgbdOdometry, AlignsSyntheticFramesFromIdentityToThreeMillimetres) {
  gslam::test::TempDir dir;
  const app::Dataset d = synthetic(dir, 7, 30);
  const tracking::OdometryConfig config;
  const tracking::OdometryFrame ref(d.load(0), config);
  for (const std::size_t cur : {1u, 3u, 6u}) {
    const tracking::OdometryFrame frame(d.load(cur), config);
    const Eigen::Isometry3d truth = true_motion(d, 0, cur);
    const tracking::OdometryResult r = tracking::align_rgbd(ref, frame, Eigen::Isometry3d::Identity(), config);
    const MotionError before = motion_error(Eigen::Isometry3d::Identity(), truth),
                      after = motion_error(r.T_cur_ref, truth);
    EXPECT_TRUE(r.converged) << r.reason;
    // The floor is the sampling: 3000 points a level (the default) left 0.6-1.5 mm here, 20000
    // 0.2 mm; leaving out points at depth edges and holes (the default: on real sequences it
    // halved teddy's ATE) takes away this noiseless scene's sharpest silhouettes: 1.4-2.5 mm.
    EXPECT_LT(after.translation_m, 3e-3) << "frame " << cur << ", moved " << before.translation_m * 100 << " cm";
    EXPECT_LT(after.rotation_deg, 0.08) << "frame " << cur << ", turned " << before.rotation_deg << " deg";
    EXPECT_GT(r.overlap, 0.8);
    std::printf("synthetic 0 -> %zu: motion %.1f cm / %.2f deg, error %.3f mm / %.4f deg, %d iterations\n", cur,
                before.translation_m * 100, before.rotation_deg, after.translation_m * 1e3, after.rotation_deg, r.iterations);
  }
}

// Real frames: the odometry chained as the SLAM system chains it (a new reference every fifth
// frame, each frame started from the last one's pose) over teddy's first 60 frames, against the
// motion capture. Pairwise comparisons would mostly measure the capture's own timing error
// (about half a degree at teddy's rotation rates).
TEST(RgbdOdometry, RealTeddyChainWithinOneCentimetre) {
  GSLAM_REQUIRE_SHARED_DATA(root, "tum_rgbd_fr3_teddy_first200/rgbd_dataset_freiburg3_teddy");
  app::DatasetOptions options;
  options.max_frames = 60;
  const app::Dataset d = app::open_dataset(root, options);
  const tracking::OdometryConfig config;
  std::shared_ptr<const tracking::OdometryFrame> reference;
  Eigen::Isometry3d T_world_ref = Eigen::Isometry3d::Identity(), T_world_cur = T_world_ref;
  std::vector<app::StampedPose> estimate, truth;
  for (std::size_t i = 0; i < d.entries.size(); ++i) {
    auto frame = std::make_shared<const tracking::OdometryFrame>(d.load(i), config);
    if (reference) {
      const tracking::OdometryResult r =
          tracking::align_rgbd(*reference, *frame, T_world_cur.inverse() * T_world_ref, config);
      EXPECT_TRUE(r.converged) << "frame " << i << ": " << r.reason;
      T_world_cur = T_world_ref * r.T_cur_ref.inverse();
    }
    if (i % 5 == 0) reference = frame, T_world_ref = T_world_cur;
    estimate.push_back({d.entries[i].timestamp, T_world_cur});
    if (d.entries[i].T_world_cam_truth) truth.push_back({d.entries[i].timestamp, *d.entries[i].T_world_cam_truth});
  }
  const app::TrajectoryErrors e = app::evaluate_trajectory(estimate, truth);
  std::printf("teddy, first %zu frames, odometry alone: ATE %.2f cm\n", d.entries.size(), e.ate_rmse * 100);
  EXPECT_LT(e.ate_rmse, 0.01);
}

TEST(RgbdOdometry, DepthWeightGrowsWithThePredictedBlur) {
  gslam::test::TempDir dir;
  const app::Dataset d = synthetic(dir, 2);
  tracking::OdometryConfig config;
  const tracking::OdometryFrame frame(d.load(0), config);
  const double focal = frame.levels().back().fx;  // finest level
  const double doubling_rate = config.blur_scale_px / (focal * config.exposure);
  EXPECT_EQ(tracking::blur_aware_depth_weight(config, frame, 0, 0), config.depth_weight);
  EXPECT_NEAR(tracking::blur_aware_depth_weight(config, frame, doubling_rate, 0), 2 * config.depth_weight, 1e-12);
  EXPECT_NEAR(tracking::blur_aware_depth_weight(config, frame, 3 * doubling_rate, 0), 10 * config.depth_weight, 1e-12);
  EXPECT_EQ(tracking::blur_aware_depth_weight(config, frame, std::nan(""), 0), config.depth_weight);
  EXPECT_TRUE(std::isfinite(tracking::blur_aware_depth_weight(config, frame, 1e300, 0)));
  config.blur_scale_px = 0;
  EXPECT_EQ(tracking::blur_aware_depth_weight(config, frame, doubling_rate, 0), config.depth_weight) << "0 turns it off";
}

// Why the weight grows: a camera turning at up to 3 rad/s with a 1/30 s exposure smears the
// colour by ten pixels and more, and the photometric term then pulls the pose towards the
// blurred image; depth is not blurred. Consecutive frames aligned with the weight the true
// angular rate gives are closer to the truth than with the sharp-frame weight.
TEST(RgbdOdometry, BlurAwareDepthWeightAlignsBlurredFramesBetter) {
  gslam::test::TempDir dir;
  app::SyntheticOptions o = app::SyntheticOptions::hard_motion();
  o.frames = 24;
  o.shake_peak_rate = 3.0;
  o.exposure = 1.0 / 30;
  o.blur_samples = 8;
  const app::Dataset d = gslam::test::synthetic_dataset(dir / "blurred", o);
  const tracking::OdometryConfig config;
  double sharp_error = 0, aware_error = 0, peak_weight = 0;
  for (std::size_t i = 1; i < d.entries.size(); ++i) {
    const tracking::OdometryFrame ref(d.load(i - 1), config), cur(d.load(i), config);
    const Eigen::Isometry3d truth = true_motion(d, i - 1, i);
    const double rate = Eigen::AngleAxisd(truth.linear()).angle() * o.fps;
    tracking::OdometryConfig aware = config;
    aware.depth_weight = tracking::blur_aware_depth_weight(config, cur, rate, 0);
    peak_weight = std::max(peak_weight, aware.depth_weight);
    const auto error_m = [&](const tracking::OdometryConfig& c) {
      return motion_error(
                 tracking::align_rgbd(ref, cur, Eigen::Isometry3d::Identity(), c).T_cur_ref, truth)
          .translation_m;
    };
    sharp_error += error_m(config);
    aware_error += error_m(aware);
  }
  const double pairs = static_cast<double>(d.entries.size() - 1);
  std::printf("blurred pairs: mean error %.2f mm at depth weight %.2f, %.2f mm blur-aware (up to %.2f)\n",
              sharp_error / pairs * 1e3, config.depth_weight, aware_error / pairs * 1e3, peak_weight);
  EXPECT_GT(peak_weight, 5 * config.depth_weight) << "the sequence must blur";
  EXPECT_LT(aware_error, 0.8 * sharp_error);
}

// Auto exposure: the colour gain of the generated sequence swings as exp(0.6 sin(2 pi t / 3 s)),
// from 1 at frame 0 to 1.28 six frames later. The odometry fits the gain between two frames,
// brighter and darker alike (each pair aligned both ways), to within 1%. Without the fit, the
// robust weights absorb the small changes (under 1 mm), and the 1.28x step moves the pose by
// 9.4 cm; with it, every pair is within 1.2 mm but the 0.78x step, 5.4 mm (its gain is fitted
// first from the unaligned frames: fitted later, the 1.28x step lost the pose by 26 cm).
TEST(RgbdOdometry, FitsTheColourGainOfAutoExposure) {
  gslam::test::TempDir dir;
  app::SyntheticOptions o;
  // The arc is walked over the whole sequence: at 24 frames its first ones move as the other
  // tests'.
  o.frames = 24;
  o.gain_swing = 0.6;
  const app::Dataset d = gslam::test::synthetic_dataset(dir / "seq", o);
  tracking::OdometryConfig fitted, fixed;
  fixed.estimate_brightness = false;
  const tracking::OdometryFrame first(d.load(0), fitted);
  double fitted_error = 0, fixed_error = 0;
  for (const std::size_t later : {2u, 4u, 6u}) {
    const tracking::OdometryFrame frame(d.load(later), fitted);
    const double gain =
        app::colour_gain(o, static_cast<double>(later) / o.fps) / app::colour_gain(o, 0);
    for (const bool forward : {true, false}) {
      const tracking::OdometryFrame& ref = forward ? first : frame;
      const tracking::OdometryFrame& cur = forward ? frame : first;
      const Eigen::Isometry3d truth = forward ? true_motion(d, 0, later) : true_motion(d, later, 0);
      const double expected_gain = forward ? gain : 1 / gain;
      const tracking::OdometryResult with =
          tracking::align_rgbd(ref, cur, Eigen::Isometry3d::Identity(), fitted);
      const tracking::OdometryResult without =
          tracking::align_rgbd(ref, cur, Eigen::Isometry3d::Identity(), fixed);
      EXPECT_TRUE(with.converged) << with.reason;
      EXPECT_NEAR(with.gain, expected_gain, 0.01)
          << "frame " << later << (forward ? " after" : " before") << " frame 0";
      EXPECT_EQ(without.gain, 1.0);
      const double e_with = motion_error(with.T_cur_ref, truth).translation_m,
                   e_without = motion_error(without.T_cur_ref, truth).translation_m;
      std::printf(
          "frames 0 and %zu (%s), gain %.3f (fitted %.3f): error %.2f mm fitted, %.2f mm without\n",
          later, forward ? "brighter" : "darker", expected_gain, with.gain, e_with * 1e3,
          e_without * 1e3);
      EXPECT_LT(e_with, 1e-2) << "frame " << later;
      fitted_error += e_with;
      fixed_error += e_without;
    }
  }
  EXPECT_LT(fitted_error, 0.2 * fixed_error);
}

// A black reference has no intensity to take a ratio of: the gain stays 1 and the pose finite.
TEST(RgbdOdometry, BlackReferenceLeavesTheGainAtOne) {
  gslam::test::TempDir dir;
  const app::Dataset d = synthetic(dir, 2);
  splat::RgbdFrame black = d.load(0);
  std::fill(black.rgb.begin(), black.rgb.end(), 0.f);
  const tracking::OdometryConfig config;
  const tracking::OdometryResult r = tracking::align_rgbd(
      tracking::OdometryFrame(black, config), tracking::OdometryFrame(d.load(1), config),
      Eigen::Isometry3d::Identity(), config);
  EXPECT_EQ(r.gain, 1.0);
  EXPECT_TRUE(r.T_cur_ref.matrix().allFinite());
}

// A person walking in front of the camera covers a quarter of the reference's points: a flat,
// evenly coloured surface 0.6 m away. The pose is still found, and the depth residuals' spread
// stays what it is without the person (the sensor noise), where the t-distribution's scale (which
// gives way once about a sixth of the points are occluded) grows many times over: the spread is
// what tells a lost frame.
TEST(RgbdOdometry, DepthSpreadIgnoresAnOccluderInFrontOfTheScene) {
  gslam::test::TempDir dir;
  app::SyntheticOptions o;
  o.frames = 3;  // the start of a 20-frame sequence: 8 cm a frame
  o.path_frames = 20;
  o.depth_noise = 0.0015;  // Kinect-class, as the odometry models it
  const app::Dataset d = gslam::test::synthetic_dataset(dir / "seq", o);
  splat::RgbdFrame occluded = d.load(2);
  const int w = occluded.width(), h = occluded.height();
  for (int y = 0; y < h; ++y) {
    for (int x = w * 3 / 4; x < w; ++x) {
      const std::size_t p = static_cast<std::size_t>(y) * w + x;
      occluded.depth[p] = 0.6f;
      for (int c = 0; c < 3; ++c) occluded.rgb[p * 3 + c] = 0.45f;
    }
  }
  const tracking::OdometryConfig config;
  const tracking::OdometryFrame ref(d.load(0), config);
  const tracking::OdometryResult clear = tracking::align_rgbd(
      ref, tracking::OdometryFrame(d.load(2), config), Eigen::Isometry3d::Identity(), config);
  const tracking::OdometryResult r = tracking::align_rgbd(
      ref, tracking::OdometryFrame(occluded, config), Eigen::Isometry3d::Identity(), config);
  ASSERT_TRUE(clear.converged) << clear.reason;
  ASSERT_TRUE(r.converged) << r.reason;
  const MotionError e = motion_error(r.T_cur_ref, true_motion(d, 0, 2));
  EXPECT_LT(e.translation_m, 0.003);
  EXPECT_LT(e.rotation_deg, 0.2);
  std::printf(
      "depth spread: %.3f without the person, %.3f with; t-distribution scale %.3f / %.3f\n",
      clear.depth_spread, r.depth_spread, clear.depth_scale, r.depth_scale);
  EXPECT_GT(clear.depth_spread, 0.3) << "the generated noise shows";
  EXPECT_LT(r.depth_spread, 1.3 * clear.depth_spread) << "the person barely moves the spread";
  EXPECT_GT(r.depth_scale, 5 * r.depth_spread) << "the t-distribution's scale, for contrast";
}

// Pixels left out apart from the frame (moving regions at a coarser scale) prepare the same
// pyramid as the frame copied with them in its own ignore mask, which they replaced: each block
// covers factor x factor pixels, the last row and column also the remainder.
TEST(RgbdOdometry, PixelsLeftOutApartPrepareTheFrameMaskedWithThem) {
  gslam::test::TempDir dir;
  const app::Dataset d = synthetic(dir, 1);
  splat::RgbdFrame frame = d.load(0);
  const int w = frame.width(), h = frame.height();
  frame.ignore.assign(static_cast<std::size_t>(w) * h, 0);
  for (int x = 0; x < w; ++x)
    frame.ignore[static_cast<std::size_t>(h / 3) * w + x] = 1;  // a row the frame ignores
  for (const int factor : {4, 7}) {  // 7 leaves a remainder at the synthetic frame's sizes
    ASSERT_NE(w % 7 + h % 7, 0);
    tracking::OdometryFrame::LeftOut left_out{{}, factor};
    const int bw = w / factor, bh = h / factor;
    for (int by = 0; by < bh; ++by) {
      for (int bx = 0; bx < bw; ++bx) {
        // A region of surfaces, its outline, and the last column of blocks (over the remainder).
        const bool inside = bx > bw / 4 && bx < bw / 2 && by > bh / 4 && by < bh / 2;
        const bool outline = bx >= bw / 4 && bx <= bw / 2 && by >= bh / 4 && by <= bh / 2;
        left_out.reasons.push_back(inside ? 2 : outline || bx == bw - 1 ? 1 : 0);
      }
    }
    splat::RgbdFrame masked = frame;
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const std::size_t block = static_cast<std::size_t>(std::min(y / factor, bh - 1)) * bw +
                                  std::min(x / factor, bw - 1);
        uint8_t& ignored = masked.ignore[static_cast<std::size_t>(y) * w + x];
        ignored = std::max(ignored, left_out.reasons[block]);
      }
    }
    const tracking::OdometryConfig config;
    const tracking::OdometryFrame apart(frame, config, left_out), copied(masked, config);
    ASSERT_EQ(apart.levels().size(), copied.levels().size());
    for (std::size_t level = 0; level < apart.levels().size(); ++level) {
      const tracking::OdometryFrame::Level &a = apart.levels()[level], &b = copied.levels()[level];
      EXPECT_EQ(a.ignore, b.ignore) << "factor " << factor << ", level " << level;
      EXPECT_EQ(a.points, b.points) << "factor " << factor << ", level " << level;
      EXPECT_GT(std::count(a.ignore.begin(), a.ignore.end(), 2), 0)
          << "the region reaches level " << level;
    }
  }
  const tracking::OdometryFrame::LeftOut wrong{std::vector<uint8_t>(10, 1), 4};
  try {
    const tracking::OdometryFrame refused(frame, tracking::OdometryConfig{}, wrong);
    ADD_FAILURE() << "accepted";
  } catch (const splat::Error& e) {
    EXPECT_NE(std::string(e.what()).find("10 pixels left out at factor 4 do not fit a"),
              std::string::npos)
        << e.what();
  }
}

// A frame of another part of the room shares too little with the reference: reported, not a
// confident wrong pose.
TEST(RgbdOdometry, ReportsFramesItCannotAlign) {
  gslam::test::TempDir dir;
  const app::Dataset d = synthetic(dir, 2);
  const tracking::OdometryConfig config;
  const tracking::OdometryFrame ref(d.load(0), config);
  splat::RgbdFrame far = d.load(1);
  // The next frame guessed 2 m to the side and turned 90 degrees: almost nothing in common.
  const tracking::OdometryResult r = tracking::align_rgbd(
      ref, tracking::OdometryFrame(far, config),
      Eigen::Isometry3d(Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY())) * Eigen::Translation3d(2, 0, 0), config);
  EXPECT_FALSE(r.converged);
  EXPECT_NE(r.reason.find("overlap"), std::string::npos) << r.reason;
}

// A flat, textureless wall constrains only three of six directions.
TEST(RgbdOdometry, ReportsDegenerateGeometryAndTexture) {
  splat::RgbdFrame wall;
  wall.camera.fx = wall.camera.fy = 200;
  wall.camera.cx = 80, wall.camera.cy = 60;
  wall.camera.width = 160, wall.camera.height = 120;
  wall.rgb.assign(160 * 120 * 3, 0.5f);
  wall.depth.assign(160 * 120, 2.f);
  tracking::OdometryConfig config;
  config.iterations = {5, 5};
  const tracking::OdometryFrame a(wall, config), b(wall, config);
  const tracking::OdometryResult r = tracking::align_rgbd(a, b, Eigen::Isometry3d::Identity(), config);
  EXPECT_FALSE(r.converged);
  EXPECT_NE(r.reason.find("degenerate"), std::string::npos) << r.reason;
}

TEST(RgbdOdometry, RefusesMismatchedInput) {
  splat::RgbdFrame f;
  f.camera.fx = f.camera.fy = 100;
  f.camera.width = 64, f.camera.height = 48;
  f.rgb.assign(10, 0.f);
  EXPECT_THROW(tracking::OdometryFrame(f, tracking::OdometryConfig{}), splat::Error);
  tracking::OdometryConfig bad;
  bad.finest_width = 4;
  try {
    bad.validate();
    ADD_FAILURE() << "accepted";
  } catch (const splat::Error& e) {
    EXPECT_NE(std::string(e.what()).find("finest_width: expected an integer in [16, 16384], got 4"), std::string::npos) << e.what();
  }
}

}  // namespace
