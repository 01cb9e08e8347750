// Analytic and contract checks of the forward pass.
#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "splat/cpu_reference.h"
#include "splat/error.h"
#include "support/backends.h"
#include "support/random_scene.h"

namespace {

// Contract tests run on every backend.
class RasterizerContract : public ::testing::TestWithParam<std::string> {};

splat::Camera front_camera(int width = 64, int height = 48) {
  splat::Camera cam;
  cam.width = width;
  cam.height = height;
  cam.fx = cam.fy = 50;
  cam.cx = width / 2.0;
  cam.cy = height / 2.0;
  return cam;  // identity pose: looks along +z from the origin
}

// One isotropic splat; colour given directly as the DC term.
void add_splat(splat::Gaussians& g, float x, float y, float z, float sigma, float opacity,
               float r, float gr, float b) {
  const std::size_t i = g.size();
  g.resize(i + 1);
  g.means[i * 3] = x;
  g.means[i * 3 + 1] = y;
  g.means[i * 3 + 2] = z;
  for (int a = 0; a < 3; ++a) g.log_scales[i * 3 + a] = std::log(sigma);
  g.rotations[i * 4] = 1;
  g.opacity_logits[i] = std::log(opacity / (1 - opacity));
  const float c0 = 0.28209479177387814f;
  g.sh[i * 3] = (r - 0.5f) / c0;
  g.sh[i * 3 + 1] = (gr - 0.5f) / c0;
  g.sh[i * 3 + 2] = (b - 0.5f) / c0;
}

TEST_P(RasterizerContract, EmptySceneRendersBackground) {
  GSLAM_REQUIRE_BACKEND(rasterizer, GetParam());
  splat::RenderSettings settings;
  settings.background = {0.25f, 0.5f, 0.75f};
  const auto f = rasterizer.forward(splat::Gaussians{}, front_camera(), settings);
  for (std::size_t p = 0; p < f.alpha.size(); ++p) {
    ASSERT_EQ(f.alpha[p], 0.f) << "pixel " << p;
    ASSERT_EQ(f.depth[p], 0.f) << "pixel " << p;
    for (int c = 0; c < 3; ++c) ASSERT_EQ(f.rgb[p * 3 + c], settings.background[c]) << "pixel " << p;
  }
}

TEST_P(RasterizerContract, SplatLandsWhereProjectionSaysWithExpectedPeakAlpha) {
  GSLAM_REQUIRE_BACKEND(rasterizer, GetParam());
  splat::Gaussians g;
  // Projects to (fx x/z + cx, fy y/z + cy) = (50*0.2/2 + 32, 50*(-0.1)/2 + 24) = (37, 21.5):
  // the centre of pixel (36, 21) is (36.5, 21.5), half a pixel off in x.
  add_splat(g, 0.2f, -0.1f, 2.f, 0.05f, 0.6f, 1.f, 0.5f, 0.25f);
  const splat::Camera cam = front_camera();
  const auto f = rasterizer.forward(g, cam, {});
  EXPECT_NEAR(f.means2d[0], 37.f, 1e-5f);
  EXPECT_NEAR(f.means2d[1], 21.5f, 1e-5f);
  // EWA: cov2d = sigma^2 J J^T + 0.3 I with J = [[fx/z, 0, -fx x/z^2], [0, fy/z, -fy y/z^2]].
  const double j00 = 25, j02 = -50 * 0.2 / 4, j11 = 25, j12 = -50 * -0.1 / 4, s2 = 0.05 * 0.05;
  const double a = s2 * (j00 * j00 + j02 * j02) + 0.3, b = s2 * j02 * j12,
               c = s2 * (j11 * j11 + j12 * j12) + 0.3, det = a * c - b * b;
  EXPECT_NEAR(f.conics[0], c / det, 1e-5);
  EXPECT_NEAR(f.conics[1], -b / det, 1e-6);
  EXPECT_NEAR(f.conics[2], a / det, 1e-5);
  // Pixel (36, 21) sits at offset (-0.5, 0) from the mean: sigma = 0.5 * 0.25 * conic_a.
  const std::size_t peak = 21 * cam.width + 36;
  const double expected_alpha = 0.6 * std::exp(-0.5 * 0.25 * c / det);
  EXPECT_NEAR(f.alpha[peak], expected_alpha, 1e-5);
  EXPECT_NEAR(f.rgb[peak * 3], expected_alpha * 1.0, 1e-5);
  EXPECT_NEAR(f.rgb[peak * 3 + 2], expected_alpha * 0.25, 1e-5);
  EXPECT_NEAR(f.depth_normalized[peak], 2.f, 1e-5f);
  // The brightest pixels are the two straddling x = 37.
  std::size_t best = 0;
  for (std::size_t p = 0; p < f.alpha.size(); ++p) best = f.alpha[p] > f.alpha[best] ? p : best;
  EXPECT_EQ(best / cam.width, 21u);
  EXPECT_TRUE(best % cam.width == 36 || best % cam.width == 37) << "peak at x " << best % cam.width;
}

TEST_P(RasterizerContract, NearSplatOccludesFarSplatWhateverTheInputOrder) {
  GSLAM_REQUIRE_BACKEND(rasterizer, GetParam());
  const splat::Camera cam = front_camera();
  splat::Gaussians near_first, far_first;
  add_splat(near_first, 0, 0, 2, 0.2f, 0.99f, 1, 0, 0);
  add_splat(near_first, 0, 0, 4, 0.4f, 0.99f, 0, 0, 1);
  add_splat(far_first, 0, 0, 4, 0.4f, 0.99f, 0, 0, 1);
  add_splat(far_first, 0, 0, 2, 0.2f, 0.99f, 1, 0, 0);
  const auto a = rasterizer.forward(near_first, cam, {});
  const auto b = rasterizer.forward(far_first, cam, {});
  const std::size_t centre = 24 * cam.width + 32;
  EXPECT_GT(a.rgb[centre * 3], 0.9f) << "the near red splat should cover the centre";
  EXPECT_LT(a.rgb[centre * 3 + 2], 0.05f) << "the far blue splat should be hidden";
  EXPECT_NEAR(a.depth_normalized[centre], 2.f, 0.05f);
  for (std::size_t i = 0; i < a.rgb.size(); ++i) ASSERT_EQ(a.rgb[i], b.rgb[i]) << "value " << i;
}

TEST_P(RasterizerContract, CullsBehindCameraAndOffScreen) {
  GSLAM_REQUIRE_BACKEND(rasterizer, GetParam());
  splat::Gaussians g;
  add_splat(g, 0, 0, -2, 0.1f, 0.9f, 1, 1, 1);   // behind
  add_splat(g, 50, 0, 2, 0.1f, 0.9f, 1, 1, 1);   // far off to the right
  add_splat(g, 0, 0, 0.001f, 0.1f, 0.9f, 1, 1, 1);  // inside the near plane
  const auto f = rasterizer.forward(g, front_camera(), {});
  EXPECT_EQ(f.stats.visible, 0u);
  EXPECT_EQ(f.stats.culled_depth, 2u);
  EXPECT_EQ(f.stats.culled_offscreen, 1u);
  EXPECT_EQ(f.stats.intersections, 0u);
  for (std::size_t p = 0; p < f.alpha.size(); ++p) ASSERT_EQ(f.alpha[p], 0.f) << "pixel " << p;
}

// Splats about the image's border, their means mostly outside it, half of them round (where the
// projection's bound on a radius is tightest) and half elongated and turned: each is culled
// exactly when its box (radius ceil(extend sigma_2d), computed here in double from the full
// covariance) misses the image, so that the projection's shortcut for Gaussians beside the view
// culls nothing the full test keeps.
TEST_P(RasterizerContract, SplatsBesideTheViewAreCulledExactlyWhenTheirBoxMissesTheImage) {
  GSLAM_REQUIRE_BACKEND(rasterizer, GetParam());
  // Boxes this close to the border, or radii this close to an integer, are left to rounding.
  constexpr double kRoundingGap = 1e-3;
  const splat::Camera cam = front_camera();  // 64x48, f 50, at the origin looking along +z
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0, 1);
  std::normal_distribution<double> normal;
  splat::Gaussians g;
  std::vector<int> expected;  // 1 visible, 0 off screen, -1 within rounding of the border
  for (int i = 0; i < 4000; ++i) {
    const double z = 1 + 3 * unit(rng), opacity = 0.02 + 0.97 * unit(rng);
    // x/z and y/z to 0.9: beyond the clamp of both (0.832 and 0.624, below).
    const double u = 0.9 * (2 * unit(rng) - 1), v = 0.9 * (2 * unit(rng) - 1);
    add_splat(g, float(u * z), float(v * z), float(z), 0.01f, float(opacity), 1, 1, 1);
    Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
    Eigen::Vector3d scale = Eigen::Vector3d::Constant(0.005 * std::pow(40.0, unit(rng)));
    if (i % 2 == 1) {
      q = Eigen::Quaterniond(normal(rng), normal(rng), normal(rng), normal(rng)).normalized();
      for (int a = 0; a < 3; ++a) scale[a] = 0.002 * std::pow(100.0, unit(rng));
    }
    for (int a = 0; a < 3; ++a) g.log_scales[std::size_t(i) * 3 + a] = float(std::log(scale[a]));
    const float stored[4] = {float(q.w()), float(q.x()), float(q.y()), float(q.z())};
    for (int a = 0; a < 4; ++a) g.rotations[std::size_t(i) * 4 + a] = stored[a];
    const Eigen::Quaterniond unit_q =
        Eigen::Quaterniond(stored[0], stored[1], stored[2], stored[3]).normalized();
    const Eigen::Matrix3d m = unit_q.toRotationMatrix() * scale.asDiagonal();
    const Eigen::Matrix3d sigma = m * m.transpose();
    // J's rows with x/z and y/z clamped to the field of view widened by kFovClampMargin (0.3) of
    // its tangent: 0.64 * 1.3 and 0.48 * 1.3.
    const double cu = std::clamp(u, -0.832, 0.832), cv = std::clamp(v, -0.624, 0.624);
    const Eigen::RowVector3d j0(50 / z, 0, -50 * cu / z), j1(0, 50 / z, -50 * cv / z);
    const double extend = std::min(3.33, std::sqrt(2 * std::log(opacity * 255)));
    const double reach_x = extend * std::sqrt(j0 * sigma * j0.transpose() + 0.3);
    const double reach_y = extend * std::sqrt(j1 * sigma * j1.transpose() + 0.3);
    const double rx = std::ceil(reach_x), ry = std::ceil(reach_y), mx = 50 * u + 32,
                 my = 50 * v + 24;
    const double gap = std::min({std::abs(mx + rx), std::abs(mx - rx - 64), std::abs(my + ry),
                                 std::abs(my - ry - 48), std::abs(reach_x - std::round(reach_x)),
                                 std::abs(reach_y - std::round(reach_y))});
    const bool off = mx + rx <= 0 || mx - rx >= 64 || my + ry <= 0 || my - ry >= 48;
    expected.push_back(gap < kRoundingGap ? -1 : off ? 0 : 1);
  }
  const auto f = rasterizer.forward(g, cam, {});
  std::size_t checked = 0, off = 0, off_turned = 0;
  for (std::size_t i = 0; i < expected.size(); ++i) {
    if (expected[i] < 0) continue;
    ++checked;
    off += expected[i] == 0;
    off_turned += expected[i] == 0 && i % 2 == 1;
    const bool visible = f.radii[i * 2] > 0 || f.radii[i * 2 + 1] > 0;
    ASSERT_EQ(visible, expected[i] == 1) << "splat " << i << " at (" << g.means[i * 3] << ", "
                                         << g.means[i * 3 + 1] << ", " << g.means[i * 3 + 2] << ")";
  }
  EXPECT_GT(checked, 3900u) << "few splats may sit within rounding of their border";
  EXPECT_GT(off, 500u) << "the scene must hold splats beside the view";
  EXPECT_GT(off_turned, 250u) << "and elongated, turned ones among them";
  EXPECT_EQ(f.stats.visible + f.stats.culled_offscreen, expected.size())
      << "none is faint, degenerate or out of depth";
}

TEST_P(RasterizerContract, ZeroQuaternionIsCulledAsDegenerate) {
  GSLAM_REQUIRE_BACKEND(rasterizer, GetParam());
  splat::Gaussians g;
  add_splat(g, 0, 0, 2, 0.1f, 0.9f, 1, 1, 1);
  g.rotations[0] = 0;
  const auto f = rasterizer.forward(g, front_camera(), {});
  EXPECT_EQ(f.stats.culled_degenerate, 1u);
  for (float v : f.rgb) ASSERT_TRUE(std::isfinite(v));
}

TEST(RasterizerForward, OutputIsBitIdenticalWhateverTheThreadCount) {
  gslam::test::SceneOptions options;
  options.count = 300;
  options.width = 160;
  options.height = 120;
  const auto scene = gslam::test::make_random_scene<float>(options);
  splat::ThreadPool one(1), three(3);
  const auto a = splat::reference_forward<float>(scene.gaussians, scene.camera, {}, one);
  const auto b = splat::reference_forward<float>(scene.gaussians, scene.camera, {}, three);
  ASSERT_EQ(a.rgb, b.rgb);
  ASSERT_EQ(a.alpha, b.alpha);
  ASSERT_EQ(a.depth, b.depth);
  ASSERT_EQ(a.sorted_ids, b.sorted_ids);
  splat::ImageGrads d;
  d.rgb.assign(a.rgb.size(), 0.5f);
  d.alpha.assign(a.alpha.size(), -0.25f);
  d.depth.assign(a.depth.size(), 0.1f);
  const auto ga = splat::reference_backward<float>(a, d, one);
  const auto gb = splat::reference_backward<float>(b, d, three);
  for (splat::ParamGroup group : splat::kAllParamGroups) {
    ASSERT_EQ(splat::param_group(ga.d_gaussians, group), splat::param_group(gb.d_gaussians, group))
        << splat::param_group_name(group);
  }
  ASSERT_EQ(ga.d_loss_d_pose, gb.d_loss_d_pose);
}

TEST_P(RasterizerContract, AlphaInUnitIntervalAndOutputsFinite) {
  GSLAM_REQUIRE_BACKEND(rasterizer, GetParam());
  gslam::test::SceneOptions options;
  options.count = 500;
  options.max_opacity = 0.99;
  const auto scene = gslam::test::make_random_scene<float>(options);
  const auto f = rasterizer.forward(scene.gaussians, scene.camera, {});
  for (std::size_t p = 0; p < f.alpha.size(); ++p) {
    ASSERT_GE(f.alpha[p], 0.f) << "pixel " << p;
    ASSERT_LE(f.alpha[p], 1.f) << "pixel " << p;
    ASSERT_TRUE(std::isfinite(f.depth[p])) << "pixel " << p;
  }
  for (float v : f.rgb) ASSERT_TRUE(std::isfinite(v));
}

TEST_P(RasterizerContract, RejectsMismatchedSizesNaNAndBadCamera) {
  GSLAM_REQUIRE_BACKEND(rasterizer, GetParam());
  splat::Gaussians g;
  add_splat(g, 0, 0, 2, 0.1f, 0.9f, 1, 1, 1);
  splat::Gaussians short_means = g;
  short_means.means.pop_back();
  EXPECT_THROW(
      {
        try {
          rasterizer.forward(short_means, front_camera(), {});
        } catch (const splat::Error& e) {
          EXPECT_STREQ(e.what(), "rasterize: means has 2 values, expected 3*N = 3 (N = 1 from opacity_logits)");
          throw;
        }
      },
      splat::Error);
  splat::Gaussians nan = g;
  nan.log_scales[1] = NAN;
  EXPECT_THROW(
      {
        try {
          rasterizer.forward(nan, front_camera(), {});
        } catch (const splat::Error& e) {
          EXPECT_NE(std::string(e.what()).find("log_scales of Gaussian 0 is nan"), std::string::npos) << e.what();
          throw;
        }
      },
      splat::Error);
  splat::Camera zero = front_camera();
  zero.width = 0;
  EXPECT_THROW(
      {
        try {
          rasterizer.forward(g, zero, {});
        } catch (const splat::Error& e) {
          EXPECT_NE(std::string(e.what()).find("image size is 0x48"), std::string::npos) << e.what();
          throw;
        }
      },
      splat::Error);
}

INSTANTIATE_TEST_SUITE_P(Backends, RasterizerContract,
                         ::testing::ValuesIn(gslam::test::backend_names()),
                         [](const auto& info) { return info.param; });

}  // namespace
