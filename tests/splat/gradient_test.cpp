// The backward pass against central finite differences, in double, on random smooth scenes:
// every parameter group and all six pose directions, with colour, alpha and depth losses.
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "splat/cpu_reference.h"
#include "splat/se3.h"
#include "support/gradient_check.h"
#include "support/random_scene.h"

namespace {

using gslam::test::Scene;
using gslam::test::SceneOptions;

// Fixed random weights per output pixel: loss = sum w_rgb.rgb + w_a.alpha + w_d.depth.
struct LinearLoss {
  splat::ImageGradsT<double> weights;

  LinearLoss(int width, int height, uint32_t seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1, 1);
    const std::size_t pixels = static_cast<std::size_t>(width) * height;
    for (std::size_t i = 0; i < pixels * 3; ++i) weights.rgb.push_back(u(rng));
    for (std::size_t i = 0; i < pixels; ++i) weights.alpha.push_back(u(rng));
    for (std::size_t i = 0; i < pixels; ++i) weights.depth.push_back(0.3 * u(rng));
  }

  std::vector<double> terms(const splat::ForwardResultT<double>& f) const {
    std::vector<double> t;
    for (std::size_t i = 0; i < f.rgb.size(); ++i) t.push_back(weights.rgb[i] * f.rgb[i]);
    for (std::size_t i = 0; i < f.alpha.size(); ++i) t.push_back(weights.alpha[i] * f.alpha[i]);
    for (std::size_t i = 0; i < f.depth.size(); ++i) t.push_back(weights.depth[i] * f.depth[i]);
    return t;
  }
};

struct GradientCase {
  uint32_t seed;
  int sh_degree;
  int count;
  bool background;
};

class RasterizerGradients : public ::testing::TestWithParam<GradientCase> {
 protected:
  void SetUp() override {
    const GradientCase param = GetParam();
    SceneOptions options;
    options.seed = param.seed;
    options.sh_degree = param.sh_degree;
    options.count = param.count;
    scene_ = gslam::test::make_random_scene<double>(options);
    if (param.background) settings_.background = {0.2f, 0.5f, 0.9f};
  }
  Scene<double> scene_;
  splat::RenderSettings settings_;
  splat::ThreadPool pool_{2};
};

TEST_P(RasterizerGradients, MatchFiniteDifferencesForEveryParameterAndPose) {
  const GradientCase param = GetParam();
  Scene<double>& scene = scene_;
  const splat::RenderSettings& settings = settings_;
  splat::ThreadPool& pool = pool_;
  const LinearLoss loss_of(scene.camera.width, scene.camera.height, param.seed + 100);

  const auto forward = splat::reference_forward<double>(scene.gaussians, scene.camera, settings, pool);
  ASSERT_EQ(forward.stats.visible, scene.gaussians.size()) << "every splat should be on screen";
  const auto grads = splat::reference_backward<double>(forward, loss_of.weights, pool);

  splat::GaussiansT<double>& g = scene.gaussians;
  auto loss = [&] {
    return loss_of.terms(splat::reference_forward<double>(g, scene.camera, settings, pool));
  };
  for (splat::ParamGroup group : splat::kAllParamGroups) {
    std::vector<double>& values = splat::param_group(g, group);
    gslam::test::expect_gradients_match(
        splat::param_group_name(group), splat::param_group(grads.d_gaussians, group),
        [&](std::size_t i, double delta) { values[i] += delta; }, loss);
  }
  const Eigen::Isometry3d pose = scene.camera.T_cam_world;
  splat::Vector6d delta = splat::Vector6d::Zero();
  gslam::test::expect_gradients_match(
      "pose", std::span<const double>(grads.d_loss_d_pose.data(), 6),
      [&](std::size_t i, double step) {
        delta[static_cast<long>(i)] += step;
        scene.camera.T_cam_world = splat::se3_exp(delta) * pose;
      },
      loss);
}

// The forward-mode pose Jacobian against central differences of every output pixel, and
// against the (separately checked) reverse-mode pose gradient of a weighted sum.
TEST_P(RasterizerGradients, PoseJacobianMatchesFiniteDifferencesAndBackward) {
  const GradientCase param = GetParam();
  Scene<double>& scene = scene_;
  const splat::RenderSettings& settings = settings_;
  splat::ThreadPool& pool = pool_;
  const auto forward = splat::reference_forward<double>(scene.gaussians, scene.camera, settings, pool);
  std::vector<double> jac;
  splat::reference_pose_jacobian<double>(forward, pool, jac);
  const std::size_t pixels = forward.alpha.size();
  ASSERT_EQ(jac.size(), pixels * 5 * 6);
  const LinearLoss loss_of(scene.camera.width, scene.camera.height, param.seed + 100);
  // Sum_p w_p . J_p must be the backward pass's pose gradient.
  splat::Vector6d via_jvp = splat::Vector6d::Zero();
  for (std::size_t p = 0; p < pixels; ++p) {
    for (int k = 0; k < 6; ++k) {
      for (int c = 0; c < 3; ++c) via_jvp[k] += loss_of.weights.rgb[p * 3 + c] * jac[(p * 5 + c) * 6 + k];
      via_jvp[k] += loss_of.weights.depth[p] * jac[(p * 5 + 3) * 6 + k];
      via_jvp[k] += loss_of.weights.alpha[p] * jac[(p * 5 + 4) * 6 + k];
    }
  }
  const auto grads = splat::reference_backward<double>(forward, loss_of.weights, pool);
  for (int k = 0; k < 6; ++k) {
    EXPECT_NEAR(via_jvp[k], grads.d_loss_d_pose[k], 1e-9 * (1 + std::abs(grads.d_loss_d_pose[k]))) << "direction " << k;
  }
  // Every entry against central differences of that output pixel, one direction at a time.
  const Eigen::Isometry3d pose = scene.camera.T_cam_world;
  auto outputs_at = [&](int k, double step) {
    splat::Vector6d delta = splat::Vector6d::Zero();
    delta[k] = step;
    splat::Camera cam = scene.camera;
    cam.T_cam_world = splat::se3_exp(delta) * pose;
    const auto f = splat::reference_forward<double>(scene.gaussians, cam, settings, pool);
    std::vector<double> v(pixels * 5);
    for (std::size_t p = 0; p < pixels; ++p) {
      for (int c = 0; c < 3; ++c) v[p * 5 + c] = f.rgb[p * 3 + c];
      v[p * 5 + 3] = f.depth[p];
      v[p * 5 + 4] = f.alpha[p];
    }
    return v;
  };
  // Two step sizes: a wrong entry disagrees at both, while a splat crossing the 1/255 alpha cut
  // inside [-h, h] (a true discontinuity) almost never does at both.
  constexpr double kSteps[2] = {1e-6, 1e-6 / 16};
  for (int k = 0; k < 6; ++k) {
    std::vector<double> numeric[2];
    for (int s = 0; s < 2; ++s) {
      const std::vector<double> plus = outputs_at(k, kSteps[s]), minus = outputs_at(k, -kSteps[s]);
      for (std::size_t i = 0; i < plus.size(); ++i) numeric[s].push_back((plus[i] - minus[i]) / (2 * kSteps[s]));
    }
    double largest = 0;
    for (std::size_t i = 0; i < numeric[0].size(); ++i) largest = std::max(largest, std::abs(jac[i * 6 + k]));
    auto agrees = [&](double num, double analytic) {
      const double scale = std::max(std::abs(num), std::abs(analytic));
      return scale <= 1e-6 * largest || std::abs(num - analytic) <= 1e-4 * scale;
    };
    std::size_t mismatches = 0;
    for (std::size_t i = 0; i < numeric[0].size(); ++i) {
      const double analytic = jac[i * 6 + k];
      if (agrees(numeric[0][i], analytic) || agrees(numeric[1][i], analytic)) continue;
      ++mismatches;
      ADD_FAILURE() << "direction " << k << " pixel " << i / 5 << " output " << i % 5 << ": numeric "
                    << numeric[0][i] << " / " << numeric[1][i] << ", analytic " << analytic;
    }
    EXPECT_EQ(mismatches, 0u) << "direction " << k;
    EXPECT_GT(largest, 0) << "direction " << k;
  }
}

INSTANTIATE_TEST_SUITE_P(
    RandomScenes, RasterizerGradients,
    ::testing::Values(GradientCase{1, 3, 6, false}, GradientCase{2, 0, 10, true},
                      GradientCase{3, 1, 8, false}, GradientCase{4, 2, 12, true}),
    [](const ::testing::TestParamInfo<GradientCase>& info) {  // stable, readable test names
      const GradientCase& c = info.param;
      return "seed" + std::to_string(c.seed) + "_sh" + std::to_string(c.sh_degree) + "_n" +
             std::to_string(c.count) + (c.background ? "_background" : "");
    });

}  // namespace
