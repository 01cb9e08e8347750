// The SLAM configuration: its JSON form (`--config`, `--print-config`) and validation.
#include <fstream>

#include <gtest/gtest.h>

#include "io/slam_config_io.h"
#include "splat/error.h"
#include "support/temp_dir.h"

namespace {

std::filesystem::path write_config(const gslam::test::TempDir& dir, const std::string& json) {
  const std::filesystem::path path = dir / "config.json";
  std::ofstream(path) << json;
  return path;
}

// Expects `json` refused with an error that contains `message`.
void expect_refused(const std::string& json, const std::string& message) {
  try {
    app::slam_config_from_json(nlohmann::json::parse(json));
    ADD_FAILURE() << json << " was accepted";
  } catch (const splat::Error& e) {
    EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << json << " -> " << e.what();
  }
}

TEST(SlamConfigFile, SetsTheRefinementAndSeedingKeys) {
  gslam::test::TempDir dir;
  const app::SlamConfig c = app::load_slam_config(write_config(
      dir, R"({"refine_passes": 3, "refine_densify_passes": 2, "refine_cache_mib": 64, "tracking": {"min_step_translation": 1e-4, "min_step_rotation": 2e-4, "pyramid": [4, 2, 1], "iterations": [5, 5, 5]}, "mapping": {"refine_depth_weight": 0.25, "refine_vignetting_rate": 0.01,
              "sh_degree": 1, "seed_scale_factor": 0.8, "ssim_weight": 0.2, "refine_seed_depth_holes": false, "window": 6.0}})"));
  EXPECT_EQ(c.refine_passes, 3);
  EXPECT_EQ(c.refine_densify_passes, 2);
  EXPECT_EQ(c.refine_cache_mib, 64);
  EXPECT_FALSE(c.mapping.refine_seed_depth_holes);
  EXPECT_EQ(c.tracking.min_step_translation, 1e-4);
  EXPECT_EQ(c.tracking.min_step_rotation, 2e-4);
  EXPECT_EQ(c.tracking.pyramid, (std::vector<int>{4, 2, 1}));
  EXPECT_EQ(c.mapping.refine_depth_weight, 0.25);
  EXPECT_EQ(c.mapping.refine_vignetting_rate, 0.01);
  EXPECT_EQ(c.mapping.seed.sh_degree, 1);
  EXPECT_EQ(c.mapping.seed.scale_factor, 0.8);
  EXPECT_EQ(c.mapping.ssim_weight, 0.2);
  EXPECT_EQ(c.mapping.window, 6) << "an integral number is an integer";
  EXPECT_EQ(c.mapping.depth_weight, app::SlamConfig{}.mapping.depth_weight) << "keys not given keep their defaults";
}

// The defaults are the tuned values, declared once: the tracking and mapping structs hold what a
// run uses, so their headers tell the truth.
TEST(SlamConfigFile, TheLibraryDefaultsAreTheSystemDefaults) {
  const app::SlamConfig c;
  EXPECT_EQ(c.tracking.pyramid, tracking::TrackingConfig{}.pyramid);
  EXPECT_EQ(c.mapping.iterations, mapping::MapperConfig{}.iterations);
  EXPECT_EQ(app::slam_config_to_json(c), app::slam_config_to_json(app::slam_config_from_json(nlohmann::json::object())));
  EXPECT_NO_THROW(c.validate());
}

// The sweep's visits: whole densifying passes, then the later passes up to refine_max_visits.
TEST(SlamConfigFile, SweepVisitsStopAtTheCapAfterTheDensifyingPasses) {
  app::SlamConfig c;
  c.refine_passes = 12;
  c.refine_densify_passes = 1;
  c.refine_max_visits = 2400;
  EXPECT_EQ(c.sweep_visits(193).densifying, 193u);
  EXPECT_EQ(c.sweep_visits(193).total, 193u * 12) << "under the cap: every pass";
  EXPECT_EQ(c.sweep_visits(700).densifying, 700u);
  EXPECT_EQ(c.sweep_visits(700).total, 2400u);
  EXPECT_EQ(c.sweep_visits(3000).total, 3000u) << "the densifying pass is never cut";
  c.refine_max_visits = 0;
  EXPECT_EQ(c.sweep_visits(10).total, 10u);
  c.refine_densify_passes = 0;
  EXPECT_EQ(c.sweep_visits(10).total, 0u);
  c.refine_passes = 0;
  c.refine_densify_passes = 1;
  c.refine_max_visits = 2400;
  EXPECT_EQ(c.sweep_visits(10).total, 0u) << "no passes, no visits";
}

// The coarse passes come right after the densifying ones; under the cap they keep their share of
// the later visits, so the last visits stay at the sweep's full resolution.
TEST(SlamConfigFile, CoarseVisitsKeepTheirShareOfTheLaterPasses) {
  app::SlamConfig c;
  c.refine_passes = 7;
  c.refine_densify_passes = 1;
  c.refine_coarse_passes = 4;
  c.refine_max_visits = 2400;
  EXPECT_EQ(c.sweep_visits(193).coarse, 193u * 4) << "under the cap: whole passes";
  EXPECT_EQ(c.sweep_visits(700).total, 2400u);
  EXPECT_EQ(c.sweep_visits(700).coarse, (2400u - 700) * 4 / 6) << "4 of the 6 later passes' share";
  c.refine_coarse_passes = 9;
  EXPECT_EQ(c.sweep_visits(193).coarse, 193u * 6) << "at most every later pass";
  c.refine_coarse_passes = 0;
  EXPECT_EQ(c.sweep_visits(193).coarse, 0u);
  c.refine_coarse_passes = 4;
  c.refine_densify_passes = 7;
  EXPECT_EQ(c.sweep_visits(193).coarse, 0u) << "no later passes";
}

// What --print-config writes, --config reads back unchanged, non-default values included.
TEST(SlamConfigFile, PrintedConfigurationReadsBackUnchanged) {
  app::SlamConfig c;
  c.refine_passes = 7;
  c.tracking.pyramid = {8, 4, 2};
  c.tracking.iterations = {3, 2, 1};
  c.tracking.depth_sigma = 0.1234567890123;
  c.mapping.isotropic = true;
  c.mapping.max_keyframes = 9;
  c.mapping.random_seed = 4000000000u;
  const nlohmann::json printed = app::slam_config_to_json(c);
  const nlohmann::json again = app::slam_config_to_json(app::slam_config_from_json(nlohmann::json::parse(printed.dump(2))));
  EXPECT_EQ(printed, again);
  EXPECT_EQ(again.at("tracking").at("depth_sigma").get<double>(), 0.1234567890123);
  EXPECT_EQ(again.at("mapping").at("random_seed").get<uint32_t>(), 4000000000u);
}

TEST(SlamConfigFile, RefusesMalformedDocumentsNamingTheKeyPath) {
  expect_refused(R"([1, 2])", "expected a JSON object of settings");
  expect_refused(R"(null)", "expected a JSON object of settings");
  expect_refused(R"({"keyframe_evry": 5})", "keyframe_evry: unknown setting");
  expect_refused(R"({"mapping": {"windw": 3}})", "mapping.windw: unknown setting");
  expect_refused(R"({"tracking": 5})", "tracking: expected an object of settings, got 5");
  expect_refused(R"({"mapping": {"window": 3.7}})", "mapping.window: expected an integer");
  expect_refused(R"({"mapping": {"window": 3.7}})", "got 3.7");
  expect_refused(R"({"mapping": {"window": true}})", "mapping.window: expected an integer in [-2147483648, 2147483647], got true");
  expect_refused(R"({"refine_passes": 4294967297})", "refine_passes: expected an integer in [-2147483648, 2147483647], got 4294967297");
  expect_refused(R"({"mapping": {"random_seed": -1}})", "mapping.random_seed: expected an integer in [0, 4294967295], got -1");
  expect_refused(R"({"mapping": {"max_keyframes": 1e30}})", "mapping.max_keyframes: expected an integer");
  expect_refused(R"({"keyframe_translation": "5 cm"})", R"(keyframe_translation: expected a finite number, got "5 cm")");
  expect_refused(R"({"refine_all_frames": 1})", "refine_all_frames: expected true or false, got 1");
  expect_refused(R"({"tracking": {"pyramid": [4, 2.5]}})", "tracking.pyramid[1]: expected an integer");
  expect_refused(R"({"tracking": {"pyramid": 4}})", "tracking.pyramid: expected a list of integers, got 4");
}

TEST(SlamConfigFile, RefusesOutOfRangeValuesNamingFieldValueAndRange) {
  expect_refused(R"({"mapping": {"window": 0}})", "mapping.window: expected an integer >= 1, got 0");
  expect_refused(R"({"mapping": {"refine_depth_weight": -1}})", "mapping.refine_depth_weight: expected a number >= 0, got -1");
  expect_refused(R"({"mapping": {"refine_vignetting_rate": -0.1}})", "mapping.refine_vignetting_rate: expected a number >= 0, got -0.1");
  expect_refused(R"({"mapping": {"sh_degree": 4}})", "mapping.sh_degree: expected an integer in [0, 3], got 4");
  expect_refused(R"({"mapping": {"seed_scale_factor": 0}})", "mapping.seed_scale_factor: expected a number > 0, got 0");
  expect_refused(R"({"mapping": {"densify_alpha": 1.5}})", "mapping.densify_alpha: expected a number in [0, 1], got 1.5");
  expect_refused(R"({"tracking": {"min_step_rotation": -1}})", "tracking.min_step_rotation: expected a number >= 0, got -1");
  expect_refused(R"({"tracking": {"pyramid": [4, 0], "iterations": [1, 1]}})", "tracking.pyramid: expected an integer >= 1, got 0");
  expect_refused(R"({"tracking": {"pyramid": [4, 2, 1]}})", "tracking.iterations: expected one count per pyramid level (3), got 2 counts");
  expect_refused(R"({"refine_cache_mib": -1})", "refine_cache_mib: expected a number >= 0, got -1");
  expect_refused(R"({"refine_coarse_passes": -1})",
                 "refine_coarse_passes: expected an integer >= 0, got -1");
  expect_refused(R"({"refine_coarse_learning_rate_scale": 0})",
                 "refine_coarse_learning_rate_scale: expected a number > 0, got 0");
  expect_refused(R"({"keyframe_every": 0})", "keyframe_every: expected an integer >= 1, got 0");
}

TEST(SlamConfigFile, FileErrorsNameThePath) {
  gslam::test::TempDir dir;
  const auto path = write_config(dir, R"({"mapping": {"window": 0}})");
  try {
    app::load_slam_config(path);
    ADD_FAILURE() << "accepted";
  } catch (const splat::Error& e) {
    EXPECT_NE(std::string(e.what()).find(path.string() + ": mapping.window"), std::string::npos) << e.what();
  }
  const auto broken = write_config(dir, R"({"mapping": )");
  EXPECT_THROW(app::load_slam_config(broken), splat::Error);
  EXPECT_THROW(app::load_slam_config(dir / "missing.json"), splat::Error);
}

}  // namespace
