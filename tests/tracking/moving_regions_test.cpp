// Moving regions (tracking/moving_regions.h): what changed between a reference and a frame at a
// known pose, on frames built here: a textured wall with and without objects in front of it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "splat/error.h"
#include "tracking/moving_regions.h"
#include "tracking/rgbd_odometry.h"

namespace {

constexpr int kWidth = 160, kHeight = 120;

// A wall 2 m away, checkered, with optional boxes at 1 m covering [x0, x1) x [y0, y1).
struct Block {
  int x0, y0, x1, y1;
};
splat::RgbdFrame wall(const std::vector<Block>& blocks = {}) {
  splat::RgbdFrame f;
  f.camera.width = kWidth, f.camera.height = kHeight;
  f.camera.fx = f.camera.fy = 130, f.camera.cx = kWidth / 2.0, f.camera.cy = kHeight / 2.0;
  f.rgb.assign(kWidth * kHeight * 3, 0.f);
  f.depth.assign(kWidth * kHeight, 2.f);
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      const float c = ((x / 8 + y / 8) % 2) ? 0.8f : 0.3f;
      for (int k = 0; k < 3; ++k) f.rgb[(y * kWidth + x) * 3 + k] = c;
    }
  }
  for (const Block& b : blocks) {
    for (int y = b.y0; y < b.y1; ++y) {
      for (int x = b.x0; x < b.x1; ++x) f.depth[y * kWidth + x] = 1.f;
    }
  }
  return f;
}

tracking::OdometryConfig one_level() {
  tracking::OdometryConfig c;
  c.iterations = {5};
  c.finest_width = kWidth;
  return c;
}

std::size_t count(const std::vector<uint8_t>& labels, uint8_t label) {
  return static_cast<std::size_t>(std::count(labels.begin(), labels.end(), label));
}

std::vector<uint8_t> regions(const splat::RgbdFrame& reference, const splat::RgbdFrame& current,
                             const std::vector<uint8_t>& previous = {}) {
  const tracking::OdometryConfig odometry = one_level();
  tracking::MovingConfig config;
  config.grow_px = 0;
  return tracking::moving_regions(tracking::OdometryFrame(reference, odometry), tracking::OdometryFrame(current, odometry),
                                  Eigen::Isometry3d::Identity(), odometry, config, previous);
}

TEST(MovingRegions, NothingMovedNothingFound) {
  const std::vector<uint8_t> labels = regions(wall({{40, 30, 80, 90}}), wall({{40, 30, 80, 90}}));
  ASSERT_EQ(labels.size(), static_cast<std::size_t>(kWidth * kHeight));
  EXPECT_EQ(count(labels, tracking::kStaticPixel), labels.size());
}

TEST(MovingRegions, AnObjectThatArrivedAndTheWallWhereOneLeft) {
  // The reference has a box on the left; in the frame it is gone, and one stands on the right.
  const std::vector<uint8_t> labels = regions(wall({{10, 30, 40, 90}}), wall({{100, 30, 140, 90}}));
  // Inside both boxes, away from their outlines (where the 3x3 neighbourhood sees both depths).
  std::size_t arrived_inside = 0, left_inside = 0;
  for (int y = 32; y < 88; ++y) {
    for (int x = 102; x < 138; ++x) arrived_inside += labels[y * kWidth + x] == tracking::kArrived;
    for (int x = 12; x < 38; ++x) left_inside += labels[y * kWidth + x] == tracking::kLeft;
  }
  EXPECT_EQ(arrived_inside, 56u * 36u);
  EXPECT_EQ(left_inside, 56u * 26u);
  // Nothing else: the wall around them is unchanged (the outlines are 1 pixel at most).
  EXPECT_LE(count(labels, tracking::kArrived), 40u * 60u);
  EXPECT_LE(count(labels, tracking::kLeft), 30u * 60u);
}

TEST(MovingRegions, SpecklesAreNoiseUnlessTheyContinueARegion) {
  // 7x7 pixels: below min_region (0.4% of 160x120: 77 pixels), above half of it.
  const splat::RgbdFrame reference = wall(), speckle = wall({{70, 50, 77, 57}});
  EXPECT_EQ(count(regions(reference, speckle), tracking::kArrived), 0u);
  std::vector<uint8_t> previous(kWidth * kHeight, 0);
  for (int y = 45; y < 60; ++y) {
    for (int x = 65; x < 80; ++x) previous[y * kWidth + x] = tracking::kArrived;
  }
  EXPECT_GT(count(regions(reference, speckle, previous), tracking::kArrived), 40u);
}

// The reference found a box moving (its pixels ignored). Moved on by a few pixels in the frame,
// the box is found whole, not just where it uncovers the wall; standing still, it joins the scene.
TEST(MovingRegions, AnObjectTheReferenceSawMovingStaysMovingUntilItStops) {
  splat::RgbdFrame reference = wall({{40, 30, 80, 90}});
  reference.ignore.assign(reference.depth.size(), 0);
  for (int y = 30; y < 90; ++y) {
    for (int x = 40; x < 80; ++x) reference.ignore[y * kWidth + x] = tracking::kMovingSurface;
  }
  std::size_t inside = 0;
  const std::vector<uint8_t> moved = regions(reference, wall({{50, 30, 90, 90}}));
  for (int y = 31; y < 89; ++y) {
    for (int x = 51; x < 89; ++x) inside += moved[y * kWidth + x] == tracking::kArrived;
  }
  EXPECT_EQ(inside, 58u * 38u);
  EXPECT_EQ(count(regions(reference, wall({{40, 30, 80, 90}})), tracking::kStaticPixel), reference.depth.size());
}

TEST(MovingRegions, DepthNoiseIsNotMotion) {
  // Kinect-class noise (1.5 mm at 1 m: 6 mm at 2 m) in every pixel of the frame.
  splat::RgbdFrame noisy = wall();
  for (std::size_t i = 0; i < noisy.depth.size(); ++i) noisy.depth[i] += 0.006f * std::sin(static_cast<float>(i) * 12.9898f);
  EXPECT_EQ(count(regions(wall(), noisy), tracking::kStaticPixel), noisy.depth.size());
}

TEST(MovingRegions, GrowingSpreadsRegionsByTheirOutline) {
  std::vector<uint8_t> labels(10 * 10, 0);
  labels[5 * 10 + 5] = tracking::kLeft;
  const std::vector<uint8_t> grown = tracking::grow_regions(labels, 10, 10, 1);
  EXPECT_EQ(grown[5 * 10 + 5], tracking::kLeft);  // a pixel keeps its own label
  EXPECT_EQ(grown[5 * 10 + 6], tracking::kOutline);
  EXPECT_EQ(grown[5 * 10 + 7], tracking::kStaticPixel);
}

TEST(MovingRegions, RefusesFramesOfOtherSizes) {
  const tracking::OdometryConfig odometry = one_level();
  EXPECT_THROW(tracking::moving_regions(tracking::OdometryFrame(wall(), odometry), tracking::OdometryFrame(wall(), odometry),
                                        Eigen::Isometry3d::Identity(), odometry, {}, std::vector<uint8_t>(7, 0)),
               splat::Error);
}

}  // namespace
