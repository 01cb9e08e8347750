// Pruning: faint Gaussians always go; oversized ones only when asked, as the final sweep's prune
// after its last visit keeps them (no visit is left to fill where they were).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "datasets/dataset.h"
#include "datasets/synthetic_sequence.h"
#include "mapping/mapper.h"
#include "support/backends.h"
#include "support/synthetic_dataset.h"
#include "support/temp_dir.h"

namespace {

void check_pruning(splat::Rasterizer& rasterizer) {
  gslam::test::TempDir dir;
  app::SyntheticOptions o;
  o.frames = 1;
  const app::Dataset dataset = gslam::test::synthetic_dataset(dir / "seq", o);
  mapping::MapperConfig config;
  config.iterations = 2;
  mapping::Mapper seeded(rasterizer, config);
  const splat::RgbdFrame frame = dataset.load(0);
  seeded.add_keyframe(frame, dataset.entries[0].T_world_cam_truth->inverse());

  // One Gaussian twice prune_max_scale along one axis, another below prune_opacity.
  mapping::MapperState state = seeded.state();
  ASSERT_GT(state.map.size(), 2u);
  const float big = static_cast<float>(std::log(2 * config.prune_max_scale));
  const float faint = static_cast<float>(std::log(0.5 * config.prune_opacity / (1 - 0.5 * config.prune_opacity)));
  state.map.log_scales[1] = big;
  state.map.opacity_logits[2] = faint;
  const std::size_t n = state.map.size();
  mapping::Mapper mapper(rasterizer, config);
  mapper.restore(std::move(state), [&](std::size_t) { return frame; });
  // How many of the map's values in `field` equal `value`.
  auto count = [&](std::vector<float> splat::Gaussians::*field, float value) {
    const std::vector<float>& values = mapper.map().*field;
    return std::count(values.begin(), values.end(), value);
  };
  auto count_scale = [&](float log_scale) { return count(&splat::Gaussians::log_scales, log_scale); };
  auto count_opacity = [&](float logit) { return count(&splat::Gaussians::opacity_logits, logit); };
  ASSERT_EQ(count_scale(big), 1);
  ASSERT_EQ(count_opacity(faint), 1);

  const mapping::Mapper::Pruned faint_only = mapper.prune(false);
  EXPECT_EQ(faint_only.gaussians, 1u);
  EXPECT_EQ(mapper.size(), n - 1);
  EXPECT_EQ(count_opacity(faint), 0) << "the faint one went";
  EXPECT_EQ(count_scale(big), 1) << "the oversized one stayed";

  const mapping::Mapper::Pruned all = mapper.prune();
  EXPECT_EQ(all.gaussians, 1u);
  EXPECT_EQ(mapper.size(), n - 2);
  EXPECT_EQ(count_scale(big), 0) << "the oversized one went";
}

TEST(Prune, KeepsOversizedGaussiansOnlyWhenAskedOnTheCpu) {
  GSLAM_REQUIRE_BACKEND(cpu, "cpu");
  check_pruning(cpu);
}

TEST(Prune, KeepsOversizedGaussiansOnlyWhenAskedOnTheResidentMap) {
  GSLAM_REQUIRE_BACKEND(vulkan, "vulkan");
  check_pruning(vulkan);
}

}  // namespace
