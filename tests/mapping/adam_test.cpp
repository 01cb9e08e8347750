#include <gtest/gtest.h>

#include "mapping/gaussian_adam.h"
#include "support/expect_error.h"
#include "support/random_scene.h"

namespace {

splat::Gaussians map_of(int n) {
  gslam::test::SceneOptions o;
  o.count = n;
  o.sh_degree = 1;
  return gslam::test::make_random_scene<float>(o).gaussians;
}

// Gradient that differs per Gaussian so moments identify their owner.
splat::GaussianGrads grads_for(const splat::Gaussians& map) {
  splat::GaussianGrads g = map;
  for (splat::ParamGroup group : splat::kAllParamGroups) {
    auto& values = splat::param_group(g, group);
    const std::size_t width = static_cast<std::size_t>(splat::param_group_width(group, map.sh_degree));
    for (std::size_t i = 0; i < values.size(); ++i) values[i] = 0.01f * static_cast<float>(i / width + 1);
  }
  return g;
}

TEST(GaussianAdam, FirstStepMovesEachParameterByItsLearningRate) {
  splat::Gaussians map = map_of(3);
  const splat::Gaussians before = map;
  mapping::GaussianAdam adam;
  adam.step(map, grads_for(map));
  // Adam's first step is lr * sign(g) (bias-corrected m/sqrt(v) = 1).
  EXPECT_NEAR(before.means[4] - map.means[4], adam.config().means, 1e-7);
  EXPECT_NEAR(before.opacity_logits[2] - map.opacity_logits[2], adam.config().opacity_logits, 1e-6);
  EXPECT_NEAR(before.sh[0] - map.sh[0], adam.config().sh_dc, 1e-6);
  EXPECT_NEAR(before.sh[5] - map.sh[5], adam.config().sh_rest, 1e-7);
}

TEST(GaussianAdam, LearningRateScaleScalesTheStep) {
  splat::Gaussians map = map_of(3);
  const splat::Gaussians before = map;
  mapping::GaussianAdam adam;
  adam.step(map, grads_for(map), 0.25);
  EXPECT_NEAR(before.means[4] - map.means[4], 0.25 * adam.config().means, 1e-7);
  EXPECT_NEAR(before.log_scales[1] - map.log_scales[1], 0.25 * adam.config().log_scales, 1e-6);
}

TEST(GaussianAdam, StateStaysAlignedWhenGaussiansAreRemovedAndAppended) {
  splat::Gaussians map = map_of(5);
  mapping::GaussianAdam adam;
  adam.step(map, grads_for(map));
  adam.step(map, grads_for(map));
  const splat::Gaussians m_before = adam.first_moment();
  // Remove Gaussians 1 and 3, then append two new ones.
  const std::vector<uint8_t> keep = {1, 0, 1, 0, 1};
  mapping::remove_gaussians(map, keep);
  adam.remove(keep);
  ASSERT_EQ(map.size(), 3u);
  ASSERT_EQ(adam.size(), 3u);
  const std::size_t survivors[] = {0, 2, 4};
  for (std::size_t j = 0; j < 3; ++j) {
    EXPECT_EQ(adam.first_moment().means[j * 3], m_before.means[survivors[j] * 3]) << "survivor " << j;
    EXPECT_EQ(adam.steps()[j], 2u);
  }
  map.resize(5);
  for (std::size_t i = 3; i < 5; ++i) map.rotations[i * 4] = 1;
  adam.append(2, map.sh_degree);
  EXPECT_EQ(adam.first_moment().means[3 * 3], 0.f);
  adam.step(map, grads_for(map));
  EXPECT_EQ(adam.steps()[0], 3u);
  EXPECT_EQ(adam.steps()[4], 1u) << "new Gaussians start their own bias correction";
}

// Steps on a pool (ranges of Gaussians on each thread) move every parameter and moment exactly
// as serial steps do; 10,000 Gaussians span several ranges, the last one partial.
TEST(GaussianAdam, StepsOnThreadsEqualSerialSteps) {
  splat::Gaussians serial = map_of(10000), threaded = serial;
  mapping::GaussianAdam serial_adam, threaded_adam;
  splat::ThreadPool pool(3);
  for (int step = 0; step < 3; ++step) {
    serial_adam.step(serial, grads_for(serial), 0.5);
    threaded_adam.step(threaded, grads_for(threaded), 0.5, &pool);
  }
  for (splat::ParamGroup group : splat::kAllParamGroups) {
    EXPECT_EQ(splat::param_group(threaded, group), splat::param_group(serial, group)) << splat::param_group_name(group);
    EXPECT_NE(splat::param_group(threaded, group), splat::param_group(map_of(10000), group)) << "the steps moved it";
  }
  EXPECT_EQ(threaded_adam.steps(), serial_adam.steps());
}

TEST(GaussianAdam, RejectsStateThatNoLongerMatchesTheMap) {
  splat::Gaussians map = map_of(4);
  mapping::GaussianAdam adam;
  adam.step(map, grads_for(map));
  map.resize(6);
  GSLAM_EXPECT_ERROR(adam.step(map, grads_for(map)), "the map has 6 Gaussians", "optimizer state 4");
}

}  // namespace
