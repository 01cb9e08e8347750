// gslam generate: synthetic sequences that reconstruct and benchmark read as they read real ones.
#include <gtest/gtest.h>

#include <fstream>
#include <set>

#include "app/run_gslam.h"
#include "datasets/dataset.h"
#include "datasets/synthetic_sequence.h"
#include "datasets/synthetic_suite.h"
#include "splat/error.h"
#include "support/temp_dir.h"

namespace {

using gslam::test::RunResult;
using gslam::test::TempDir;

TEST(CliGenerate, WritesASequenceThatReadsBackWithItsGroundTruth) {
  TempDir dir;
  const std::string out = (dir / "seq").string();
  const RunResult r = run_gslam("generate " + out + " --frames 4 --width 40 --height 30 --depth-holes 0.1 --focal-error 0.02");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const app::Dataset d = app::open_dataset(dir / "seq", {});
  ASSERT_EQ(d.entries.size(), 4u);
  for (const app::DatasetEntry& e : d.entries) EXPECT_TRUE(e.T_world_cam_truth.has_value());
  EXPECT_NEAR(d.intrinsics.fx, 260 * 1.02, 1e-6) << "intrinsics.txt carries the focal error";
  const splat::RgbdFrame f = d.load(0);
  EXPECT_EQ(f.width(), 40);
  EXPECT_EQ(f.height(), 30);
  std::size_t holes = 0;
  for (const float z : f.depth) holes += !(z > 0);
  EXPECT_GT(holes, 0u) << "--depth-holes leaves pixels without depth";
}

TEST(CliGenerate, DistortionIsSeenThroughAndStatedInIntrinsics) {
  TempDir dir;
  const RunResult r = run_gslam("generate " + (dir / "seq").string() +
                                " --frames 2 --width 40 --height 30 --distortion 0.1,-0.2,0.001,0");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const app::Dataset d = app::open_dataset(dir / "seq", {});
  EXPECT_EQ(d.distortion.coefficients(), (std::vector<double>{0.1, -0.2, 0.001, 0, 0}));
  EXPECT_TRUE(d.undistortion);
  const RunResult bad =
      run_gslam("generate " + (dir / "bad").string() + " --frames 2 --distortion 0.1");
  EXPECT_NE(bad.exit_code, 0);
  EXPECT_EQ(bad.output,
            "error: distortion '0.1': expected 4 or 5 distortion coefficients "
            "k1,k2,p1,p2[,k3], got 1\n");
}

TEST(CliGenerate, RefusesAFolderInUseAndOptionsTheSuiteSetsItself) {
  TempDir dir;
  const std::string out = (dir / "seq").string();
  ASSERT_EQ(run_gslam("generate " + out + " --frames 2 --width 16 --height 12").exit_code, 0);
  const RunResult again = run_gslam("generate " + out + " --frames 3 --width 16 --height 12");
  EXPECT_NE(again.exit_code, 0);
  EXPECT_EQ(again.output, "error: " + out + ": not empty; give --overwrite to replace what is there\n");
  std::ofstream(dir / "seq" / "notes.txt") << "mine\n";
  const RunResult replaced = run_gslam("generate " + out + " --frames 3 --width 16 --height 12 --overwrite");
  ASSERT_EQ(replaced.exit_code, 0) << replaced.output;
  EXPECT_EQ(app::open_dataset(dir / "seq", {}).entries.size(), 3u);
  EXPECT_TRUE(std::filesystem::exists(dir / "seq" / "notes.txt")) << "only what generate writes is replaced";
  const RunResult suite = run_gslam("generate " + (dir / "suite").string() + " --suite --frames 3");
  EXPECT_NE(suite.exit_code, 0);
  EXPECT_EQ(suite.output, "error: gslam generate: --frames describes one sequence; --suite writes its own\n");
  const RunResult rolling = run_gslam("generate " + (dir / "suite").string() + " --suite --rolling-shutter 0.03");
  EXPECT_NE(rolling.exit_code, 0) << "every option of one sequence is refused, the newest too";
  EXPECT_EQ(rolling.output, "error: gslam generate: --rolling-shutter describes one sequence; --suite writes its own\n");
  EXPECT_FALSE(std::filesystem::exists(dir / "suite"));
}

// A path shorter than the frames written would leave the camera still past its end.
TEST(SyntheticSequence, RefusesAPathShorterThanItsFrames) {
  TempDir dir;
  app::SyntheticOptions o;
  o.frames = 5;
  o.width = 16;
  o.height = 12;
  o.path_frames = 4;
  try {
    app::write_synthetic_sequence(dir / "seq", o);
    ADD_FAILURE() << "path_frames 4 under frames 5 was accepted";
  } catch (const splat::Error& e) {
    EXPECT_STREQ(e.what(), "synthetic sequence: path_frames 4 must be 0 or at least frames (5)");
  }
  o.path_frames = 5;
  EXPECT_NO_THROW(app::write_synthetic_sequence(dir / "seq", o));
}

// The suite holds each hard case that docs/tuning.md names, under distinct folder names.
TEST(SyntheticSuite, CoversTheHardCases) {
  const std::vector<app::SyntheticCase> suite = app::hard_case_suite();
  std::set<std::string> names;
  bool fast = false, blur = false, holes = false, loop = false, miscalibrated = false,
       long_one = false, moving = false, walking = false, unsynced = false, exposure = false,
       lens = false, unregistered = false, rolling = false, patterned = false;
  for (const app::SyntheticCase& c : suite) {
    EXPECT_TRUE(names.insert(c.name).second) << c.name;
    fast |= c.options.shake_peak_rate >= 2;
    blur |= c.options.exposure > 0 && c.options.blur_samples > 1;
    holes |= c.options.depth_holes >= 0.1;
    loop |= c.options.laps > 0;
    miscalibrated |= c.options.focal_error != 0;
    long_one |= c.options.frames >= 700;
    moving |= c.options.movers && !c.options.labels;  // found without a model, not from labels
    walking |= c.options.walkers && !c.options.labels;
    patterned |= c.options.walkers && c.options.patterned_walkers;
    unsynced |= c.options.depth_lag > 0;
    exposure |= c.options.gain_swing > 0;
    lens |= c.options.distortion.any();
    unregistered |= c.options.color_focal_ratio != 1;
    rolling |= c.options.rolling_shutter > 0;
  }
  EXPECT_TRUE(fast && blur && holes && loop && miscalibrated && long_one && moving && walking &&
              unsynced && exposure && lens && unregistered && rolling && patterned);
}

}  // namespace
