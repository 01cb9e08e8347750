// Lens distortion: raw frames resampled into a pinhole camera, checked against the distortion
// model written out here (independently of OpenCV, which does the resampling).
#include "datasets/lens_distortion.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "splat/error.h"
#include "support/expect_error.h"

namespace {

const app::LensDistortion kFr1{0.262383, -0.953104, -0.005358, 0.002628,
                               1.163314};  // TUM's fr1 Kinect

// The model: normalized undistorted (x, y) to normalized distorted.
Eigen::Vector2d distort(const app::LensDistortion& d, double x, double y) {
  const double r2 = x * x + y * y, radial = 1 + r2 * (d.k1 + r2 * (d.k2 + r2 * d.k3));
  return {x * radial + 2 * d.p1 * x * y + d.p2 * (r2 + 2 * x * x),
          y * radial + d.p1 * (r2 + 2 * y * y) + 2 * d.p2 * x * y};
}

splat::Camera raw_camera() {
  splat::Camera c;
  c.fx = 260, c.fy = 259, c.cx = 161.3, c.cy = 118.7;
  c.width = 320, c.height = 240;
  return c;
}

// Where pinhole pixel (i, j) of `pinhole` looks in the raw image, in our pixel coordinates
// (centres at +0.5).
Eigen::Vector2d raw_position(const splat::Camera& raw, const splat::Camera& pinhole,
                             const app::LensDistortion& d, int i, int j) {
  const Eigen::Vector2d n =
      distort(d, (i + 0.5 - pinhole.cx) / pinhole.fx, (j + 0.5 - pinhole.cy) / pinhole.fy);
  return {raw.fx * n.x() + raw.cx, raw.fy * n.y() + raw.cy};
}

// A smooth raw colour (bilinear interpolation is exact to about 1e-3 on it) and a raw depth of a
// slanted wall (1.5-2.3 m) with a box in front (0.8 m, x and y in [100, 180)) and a hole (no
// depth, x and y in [220, 240)).
double raw_colour(double u, double v) {
  return 0.5 + 0.4 * std::sin(0.05 * u) * std::cos(0.07 * v);
}
// At pixel centre (u, v): the wall's depth is linear, which bilinear interpolation keeps exactly.
double wall_depth(double u, double v) { return 1.5 + 0.002 * u + 0.001 * v; }
enum class Region { kWall, kBox, kHole };
Region region_of(int x, int y) {
  if (x >= 100 && x < 180 && y >= 100 && y < 180) return Region::kBox;
  if (x >= 220 && x < 240 && y >= 220 && y < 240) return Region::kHole;
  return Region::kWall;
}

TEST(Undistortion, ResamplesARawFrameIntoAPinholeCameraThatSeesOnlyTheRawView) {
  const splat::Camera raw = raw_camera();
  const app::Undistortion undistortion(raw, kFr1, "test");
  const splat::Camera& pinhole = undistortion.camera();
  EXPECT_EQ(pinhole.width, raw.width);
  EXPECT_EQ(pinhole.height, raw.height);
  // fr1's lens stretches the corners outwards: the pinhole camera that sees only the raw view
  // zooms in a little.
  EXPECT_GT(pinhole.fx, raw.fx);
  EXPECT_LT(pinhole.fx, raw.fx * 1.15);

  splat::RgbdFrame f;
  f.camera = raw;
  const int w = raw.width, h = raw.height;
  f.rgb.resize(static_cast<std::size_t>(w) * h * 3);
  f.depth.resize(static_cast<std::size_t>(w) * h);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      for (int c = 0; c < 3; ++c)
        f.rgb[i * 3 + c] = static_cast<float>(raw_colour(x + 0.5, y + 0.5) * (1.0 - 0.2 * c));
      const Region r = region_of(x, y);
      f.depth[i] = r == Region::kBox    ? 0.8f
                   : r == Region::kHole ? 0.0f
                                        : static_cast<float>(wall_depth(x + 0.5, y + 0.5));
    }
  }
  undistortion.apply(f);
  EXPECT_DOUBLE_EQ(f.camera.fx, pinhole.fx);
  EXPECT_DOUBLE_EQ(f.camera.cy, pinhole.cy);

  double worst_colour = 0, outside = 0;
  std::size_t made_up = 0, inside_wall = 0, wall_off = 0, inside_box = 0, box_off = 0;
  for (int j = 0; j < h; ++j) {
    for (int i = 0; i < w; ++i) {
      const std::size_t k = static_cast<std::size_t>(j) * w + i;
      const Eigen::Vector2d p = raw_position(raw, pinhole, kFr1, i, j);
      // Inside the raw image, up to the outer pixels' centres.
      outside = std::max({outside, 0.5 - p.x(), p.x() - (w - 0.5), 0.5 - p.y(), p.y() - (h - 0.5)});
      for (int c = 0; c < 3; ++c) {
        worst_colour = std::max(
            worst_colour, std::abs(f.rgb[k * 3 + c] - raw_colour(p.x(), p.y()) * (1.0 - 0.2 * c)));
      }
      const float z = f.depth[k];
      made_up += (z > 0 && z < 0.8f - 1e-6f) || (z > 0.8f + 1e-6f && z < 1.5f);
      // The four raw pixels around p all in one region: the region's own depth there.
      const int x0 = static_cast<int>(std::floor(p.x() - 0.5)),
                y0 = static_cast<int>(std::floor(p.y() - 0.5));
      const Region r = region_of(x0, y0);
      if (r != region_of(x0 + 1, y0) || r != region_of(x0, y0 + 1) ||
          r != region_of(x0 + 1, y0 + 1))
        continue;
      if (r == Region::kWall)
        ++inside_wall, wall_off += std::abs(z - wall_depth(p.x(), p.y())) > 1e-4;
      if (r == Region::kBox) ++inside_box, box_off += z != 0.8f;
    }
  }
  EXPECT_LT(outside, 0.02) << "every pinhole pixel looks inside the raw image";
  EXPECT_LT(worst_colour, 0.003)
      << "colour is the raw image's where the model says each pixel looks";
  EXPECT_EQ(made_up, 0u)
      << "no depth between the box and the wall, nor between the hole and either";
  EXPECT_GT(inside_wall, std::size_t(w * h / 2));
  EXPECT_EQ(wall_off, 0u)
      << "a surface's depth is interpolated where the model says each pixel looks";
  EXPECT_GT(inside_box, 5000u);
  EXPECT_EQ(box_off, 0u);
}

TEST(Undistortion, UndistortedCoordinatesInvertTheModel) {
  std::vector<Eigen::Vector2d> distorted;
  std::vector<Eigen::Vector2d> undistorted = {{0, 0}, {0.3, -0.2}, {-0.6, 0.45}, {0.61, 0.46}};
  for (const Eigen::Vector2d& u : undistorted) distorted.push_back(distort(kFr1, u.x(), u.y()));
  const std::vector<Eigen::Vector2d> back = app::undistort_normalized(kFr1, distorted);
  ASSERT_EQ(back.size(), undistorted.size());
  for (std::size_t i = 0; i < back.size(); ++i)
    EXPECT_LT((back[i] - undistorted[i]).norm(), 1e-9) << i;
}

// A wide barrel lens calibrated with k1 alone: its model turns back only beyond the image's
// edges, in the corners, which the pinhole view does not reach.
TEST(Undistortion, BarrelLensWithK1AloneIsAccepted) {
  splat::Camera raw;
  raw.fx = raw.fy = 525, raw.cx = 319.5, raw.cy = 239.5, raw.width = 640, raw.height = 480;
  const app::Undistortion undistortion(raw, app::LensDistortion{-0.3, 0, 0, 0, 0}, "barrel");
  EXPECT_LT(undistortion.camera().fx, raw.fx)
      << "barrel: the pinhole view is wider than the focal length says";
}

TEST(Undistortion, CoefficientsNoLensHasAreRefusedInOneLine) {
  GSLAM_EXPECT_ERROR(
      app::Undistortion(raw_camera(), app::LensDistortion{-3.0, 0, 0, 0, 0}, "cam.txt"), "cam.txt",
      "folds the 320x240 image over");
  GSLAM_EXPECT_ERROR(app::lens_distortion_from({0.1, 0.2, 0.3}, "calib"), "calib", "4 or 5");
  GSLAM_EXPECT_ERROR(app::lens_distortion_from({0.1, NAN, 0, 0}, "calib"), "calib",
                     "distortion k2 is nan", "finite");
  GSLAM_EXPECT_ERROR(app::parse_lens_distortion("0.1,x,0,0"), "distortion '0.1,x,0,0'");
}

TEST(Undistortion, RosCameraInfoDistortionModels) {
  EXPECT_FALSE(app::lens_distortion_from_ros("", {}, "info").any());
  EXPECT_FALSE(app::lens_distortion_from_ros("equidistant", {0, 0, 0, 0}, "info").any())
      << "zeros are none";
  const app::LensDistortion plumb_bob =
      app::lens_distortion_from_ros("plumb_bob", kFr1.coefficients(), "info");
  EXPECT_EQ(plumb_bob.coefficients(), kFr1.coefficients());
  const app::LensDistortion rational = app::lens_distortion_from_ros(
      "rational_polynomial", {0.1, -0.2, 0.001, 0.002, 0.05, 0, 0, 0}, "info");
  EXPECT_DOUBLE_EQ(rational.k3, 0.05);
  GSLAM_EXPECT_ERROR(
      app::lens_distortion_from_ros("equidistant", {0.1, 0.01, 0, 0}, "/cam/camera_info"),
      "/cam/camera_info", "'equidistant'", "not supported");
  GSLAM_EXPECT_ERROR(
      app::lens_distortion_from_ros("rational_polynomial", {0.1, -0.2, 0, 0, 0, 0.3, 0, 0}, "info"),
      "'rational_polynomial'");
}

}  // namespace
