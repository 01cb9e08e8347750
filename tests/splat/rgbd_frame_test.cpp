#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "splat/rgbd_frame.h"
#include "support/expect_error.h"

namespace {

splat::Camera small_camera() {
  splat::Camera c;
  c.width = 80;
  c.height = 60;
  c.fx = c.fy = 70;
  c.cx = 40;
  c.cy = 30;
  return c;
}

// Depth of the plane n . x = d (camera coordinates) at every pixel centre.
std::vector<float> plane_depth(const splat::Camera& c, const Eigen::Vector3d& n, double d) {
  std::vector<float> depth(static_cast<std::size_t>(c.width) * c.height, 0.f);
  for (int y = 0; y < c.height; ++y) {
    for (int x = 0; x < c.width; ++x) {
      const Eigen::Vector3d ray((x + 0.5 - c.cx) / c.fx, (y + 0.5 - c.cy) / c.fy, 1.0);
      depth[static_cast<std::size_t>(y) * c.width + x] = static_cast<float>(d / n.dot(ray));
    }
  }
  return depth;
}

// A tilted wall seen from a camera that then turns by 2 degrees and moves 1 cm: the depth moved
// to the new pose is the wall's depth from there, except near the edge the old view did not see.
TEST(ReprojectDepth, GivesThePlanesDepthFromTheMovedCamera) {
  const splat::Camera c = small_camera();
  const Eigen::Vector3d n = Eigen::Vector3d(0.2, -0.1, 1).normalized();
  const std::vector<float> before = plane_depth(c, n, 2.0);
  // x_after = T x_before: the camera turned about its y axis and moved along x.
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::AngleAxisd(2 * M_PI / 180, Eigen::Vector3d::UnitY()).toRotationMatrix();
  T.translation() = Eigen::Vector3d(0.01, 0, 0);
  const std::vector<float> moved = splat::reproject_depth(before, c, T);
  // In the moved camera the plane is (R n) . x = d + (R n) . t.
  const Eigen::Vector3d n_after = T.linear() * n;
  const std::vector<float> truth = plane_depth(c, n_after, 2.0 + n_after.dot(T.translation()));
  std::size_t measured = 0, inside = 0;
  for (int y = 0; y < c.height; ++y) {
    for (int x = 5; x < c.width - 5; ++x) {  // the turn brings about 2.4 px of unseen edge in
      const std::size_t i = static_cast<std::size_t>(y) * c.width + x;
      ++inside;
      if (moved[i] == 0) continue;
      ++measured;
      // A point lands on the pixel its projection falls in, within half a pixel of the centre.
      ASSERT_NEAR(moved[i], truth[i], 0.01) << "pixel " << x << ", " << y;
    }
  }
  EXPECT_GT(measured, 0.9 * static_cast<double>(inside)) << "few pixels are left unmeasured";
}

TEST(ReprojectDepth, IdentityKeepsTheDepthAndHoles) {
  const splat::Camera c = small_camera();
  std::vector<float> depth = plane_depth(c, Eigen::Vector3d::UnitZ(), 1.5);
  depth[10] = 0;
  depth[200] = 0;
  EXPECT_EQ(splat::reproject_depth(depth, c, Eigen::Isometry3d::Identity()), depth);
}

// The nearer surface wins where two land on one pixel: a box 1 m away in front of a wall 3 m
// away, the camera moved 10 cm to the right, so the box shifts 7 px left over the wall, which
// shifts only 2.3 px: the wall the box hid stays unmeasured.
TEST(ReprojectDepth, KeepsTheNearestPointOnAPixel) {
  const splat::Camera c = small_camera();
  std::vector<float> depth = plane_depth(c, Eigen::Vector3d::UnitZ(), 3.0);
  for (int y = 25; y < 35; ++y)
    for (int x = 30; x < 40; ++x) depth[static_cast<std::size_t>(y) * c.width + x] = 1.f;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(-0.1, 0, 0);
  const std::vector<float> moved = splat::reproject_depth(depth, c, T);
  for (int x = 24; x < 32; ++x) EXPECT_NEAR(moved[30 * c.width + x], 1.f, 1e-6) << "x " << x;  // the box, moved
  // Behind where the box was: wall nobody saw (unmeasured), then wall seen beside the box.
  for (int x = 34; x < 37; ++x) EXPECT_EQ(moved[30 * c.width + x], 0.f) << "x " << x;
  for (int x = 39; x < 45; ++x) EXPECT_NEAR(moved[30 * c.width + x], 3.f, 1e-6) << "x " << x;
}

TEST(ReprojectDepth, RejectsDepthOfAnotherSize) {
  const splat::Camera c = small_camera();
  GSLAM_EXPECT_ERROR(splat::reproject_depth(std::vector<float>(10, 1.f), c, Eigen::Isometry3d::Identity()),
                     "reproject_depth", "80x60");
}

// move_depth_to_colour_time moves only the depth, and marks it moved.
TEST(ReprojectDepth, FrameKeepsItsColourAndLosesItsOffset) {
  splat::RgbdFrame f;
  f.camera = small_camera();
  f.timestamp = 3;
  f.depth_time_offset = 0.01;
  f.rgb.assign(static_cast<std::size_t>(f.width()) * f.height() * 3, 0.25f);
  f.depth = plane_depth(f.camera, Eigen::Vector3d::UnitZ(), 2.0);
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.translation() = Eigen::Vector3d(0, 0, 0.1);  // the camera 10 cm back: the wall 2.1 m away
  splat::RgbdFrame moved = f;
  splat::move_depth_to_colour_time(moved, T);
  EXPECT_EQ(moved.depth_time_offset, 0.0);
  EXPECT_EQ(moved.rgb, f.rgb);
  EXPECT_EQ(moved.timestamp, 3.0);
  EXPECT_NEAR(moved.depth[30 * f.width() + 40], 2.1f, 1e-5);
}

// The box average of every factor, factor 2 included (the odometry's pyramids take its own
// unrolled path): colour averages every pixel of a block, depth only the measured ones, the
// ignore mask keeps a block's largest reason, labels its first pixel; an odd last row and
// column are dropped.
TEST(Downsample, AveragesEachBlockForEveryFactor) {
  splat::RgbdFrame f;
  f.camera.width = 13, f.camera.height = 9;
  f.camera.fx = f.camera.fy = 10, f.camera.cx = 6.5, f.camera.cy = 4.5;
  const std::size_t pixels = 13 * 9;
  f.rgb.resize(pixels * 3), f.depth.resize(pixels), f.ignore.resize(pixels), f.labels.resize(pixels);
  for (std::size_t i = 0; i < pixels; ++i) {
    for (int c = 0; c < 3; ++c) f.rgb[i * 3 + c] = static_cast<float>((i * 7 + c * 5) % 17) / 16.f;
    f.depth[i] = i % 5 == 0 ? 0.f : 1.f + static_cast<float>(i % 11) / 8.f;  // holes
    f.ignore[i] = static_cast<uint8_t>(i % 13 == 0 ? 2 : i % 7 == 0);
    f.labels[i] = static_cast<uint8_t>(i % 4);
  }
  for (int factor : {2, 3, 4}) {
    SCOPED_TRACE("factor " + std::to_string(factor));
    const splat::RgbdFrame d = splat::downsample(f, factor);
    ASSERT_EQ(d.width(), 13 / factor);
    ASSERT_EQ(d.height(), 9 / factor);
    EXPECT_DOUBLE_EQ(d.camera.fx, 10.0 / factor);
    EXPECT_DOUBLE_EQ(d.camera.cx, 6.5 / factor);
    for (int y = 0; y < d.height(); ++y) {
      for (int x = 0; x < d.width(); ++x) {
        double rgb[3] = {0, 0, 0}, depth = 0;
        int measured = 0, ignored = 0;
        for (int dy = 0; dy < factor; ++dy) {
          for (int dx = 0; dx < factor; ++dx) {
            const std::size_t i = static_cast<std::size_t>(y * factor + dy) * 13 + x * factor + dx;
            for (int c = 0; c < 3; ++c) rgb[c] += f.rgb[i * 3 + c];
            if (f.depth[i] > 0) depth += f.depth[i], ++measured;
            ignored = std::max<int>(ignored, f.ignore[i]);
          }
        }
        const std::size_t o = static_cast<std::size_t>(y) * d.width() + x;
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(d.rgb[o * 3 + c], rgb[c] / (factor * factor), 1e-6);
        EXPECT_NEAR(d.depth[o], measured ? depth / measured : 0.0, 1e-6) << x << ", " << y;
        EXPECT_EQ(d.ignore[o], ignored) << x << ", " << y;
        EXPECT_EQ(d.labels[o], f.labels[static_cast<std::size_t>(y * factor) * 13 + x * factor]);
      }
    }
  }
}

}  // namespace
