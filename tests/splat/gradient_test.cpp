// The backward pass against central finite differences, in double, on random smooth scenes:
// every parameter group and all six pose directions, with colour, alpha and depth losses.
#include <random>

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

class RasterizerGradients : public ::testing::TestWithParam<GradientCase> {};

TEST_P(RasterizerGradients, MatchFiniteDifferencesForEveryParameterAndPose) {
  const GradientCase param = GetParam();
  SceneOptions options;
  options.seed = param.seed;
  options.sh_degree = param.sh_degree;
  options.count = param.count;
  Scene<double> scene = gslam::test::make_random_scene<double>(options);
  splat::RenderSettings settings;
  if (param.background) settings.background = {0.2f, 0.5f, 0.9f};
  splat::ThreadPool pool(2);
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

INSTANTIATE_TEST_SUITE_P(
    RandomScenes, RasterizerGradients,
    ::testing::Values(GradientCase{1, 3, 6, false}, GradientCase{2, 0, 10, true},
                      GradientCase{3, 1, 8, false}, GradientCase{4, 2, 12, true}));

}  // namespace
