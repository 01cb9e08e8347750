// `--config` files: keys reach the configuration, and out-of-range values are refused with a
// message naming them.
#include <fstream>

#include <gtest/gtest.h>

#include "app/slam_config_io.h"
#include "splat/error.h"
#include "support/temp_dir.h"

namespace {

std::filesystem::path write_config(const gslam::test::TempDir& dir, const std::string& json) {
  const std::filesystem::path path = dir / "config.json";
  std::ofstream(path) << json;
  return path;
}

TEST(SlamConfigFile, SetsTheRefinementAndSeedingKeys) {
  gslam::test::TempDir dir;
  const app::SlamConfig c = app::load_slam_config(write_config(
      dir, R"({"refine_passes": 3, "refine_densify_passes": 2, "refine_cache_mib": 64, "tracking": {"min_step_translation": 1e-4, "min_step_rotation": 2e-4}, "mapping": {"refine_depth_weight": 0.25, "refine_vignetting_rate": 0.01,
              "sh_degree": 1, "seed_scale_factor": 0.8, "ssim_weight": 0.2, "refine_seed_depth_holes": true}})"));
  EXPECT_EQ(c.refine_passes, 3);
  EXPECT_EQ(c.refine_densify_passes, 2);
  EXPECT_EQ(c.refine_cache_mib, 64);
  EXPECT_TRUE(c.mapping.refine_seed_depth_holes);
  EXPECT_EQ(c.tracking.min_step_translation, 1e-4);
  EXPECT_EQ(c.tracking.min_step_rotation, 2e-4);
  EXPECT_EQ(c.mapping.refine_depth_weight, 0.25);
  EXPECT_EQ(c.mapping.refine_vignetting_rate, 0.01);
  EXPECT_EQ(c.mapping.seed.sh_degree, 1);
  EXPECT_EQ(c.mapping.seed.scale_factor, 0.8);
  EXPECT_EQ(c.mapping.ssim_weight, 0.2);
  EXPECT_EQ(c.mapping.depth_weight, app::SlamConfig{}.mapping.depth_weight) << "keys not given keep their defaults";
}

TEST(SlamConfigFile, RefusesOutOfRangeValuesNamingThem) {
  gslam::test::TempDir dir;
  const std::pair<const char*, const char*> cases[] = {
      {R"({"mapping": {"refine_depth_weight": -1}})", "loss weights must be >= 0"},
      {R"({"mapping": {"refine_vignetting_rate": -0.1}})", "refine_vignetting_rate must be >= 0"},
      {R"({"mapping": {"sh_degree": 4}})", "sh_degree must be 0 to 3"},
      {R"({"mapping": {"seed_scale_factor": 0}})", "seed scale_factor must be positive"},
      {R"({"tracking": {"min_step_rotation": -1}})", "min_step_translation and min_step_rotation must be >= 0"},
      {R"({"refine_cache_mib": -1})", "refine_cache_mib must be >= 0"},
  };
  for (const auto& [json, message] : cases) {
    try {
      app::load_slam_config(write_config(dir, json));
      ADD_FAILURE() << json << " was accepted";
    } catch (const splat::Error& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  }
}

}  // namespace
