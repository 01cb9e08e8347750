// gslam benchmark: the sequences it finds, their table against each run's own eval, a re-run
// that continues, and a sequence that fails.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include "app/run_gslam.h"
#include "batch/opencv_baseline.h"
#include "batch/sequence_finder.h"
#include "datasets/synthetic_sequence.h"
#include "support/json_file.h"
#include "support/temp_dir.h"

namespace {

using gslam::test::TempDir;

using gslam::test::read_json;

void write_sequence(const std::filesystem::path& dir, int frames) {
  app::SyntheticOptions o;
  o.frames = frames;
  app::write_synthetic_sequence(dir, o);
}

TEST(SequenceFinder, FindsEveryLayoutAtAnyDepthButNotInsideASequence) {
  TempDir dir;
  write_sequence(dir / "suite" / "a", 3);
  write_sequence(dir / "suite" / "group" / "b", 3);
  write_sequence(dir / "suite" / "a" / "nested", 3);  // inside a sequence: not searched
  std::filesystem::create_directories(dir / "suite" / "notes");
  // The images layout: lists removed.
  write_sequence(dir / "suite" / "c", 3);
  std::filesystem::remove(dir / "suite" / "c" / "rgb.txt");
  std::filesystem::remove(dir / "suite" / "c" / "depth.txt");
  // ROS recordings are sequences by their name (the reader checks their contents), also beside
  // other sequences, but not inside one; other files are not.
  gslam::test::write_text(dir / "suite" / "group" / "run.MCAP", "");
  gslam::test::write_text(dir / "suite" / "a" / "inside.bag", "");
  gslam::test::write_text(dir / "suite" / "notes" / "bag.txt", "");
  const auto found = app::find_sequences(dir / "suite");
  ASSERT_EQ(found.size(), 4u);
  EXPECT_EQ(found[0].name, "a");
  EXPECT_EQ(found[1].name, "c");
  EXPECT_EQ(found[2].name, "group_b");
  EXPECT_EQ(found[3].name, "group_run.MCAP");
  EXPECT_EQ(found[3].path, dir / "suite" / "group" / "run.MCAP");
  EXPECT_EQ(app::find_sequences(dir / "suite" / "group" / "b").front().name, "b") << "the root itself";
  EXPECT_TRUE(app::find_sequences(dir / "suite" / "notes").empty());
}

// A suite made of links to sequences kept elsewhere: the links are followed, a loop of links
// ends, and a sequence linked twice is found once.
TEST(SequenceFinder, FollowsLinksOnceEach) {
  TempDir dir;
  write_sequence(dir / "data" / "teddy", 3);
  std::filesystem::create_directories(dir / "suite");
  std::filesystem::create_directory_symlink(dir / "data" / "teddy", dir / "suite" / "teddy");
  std::filesystem::create_directory_symlink(dir / "data" / "teddy", dir / "suite" / "teddy_again");
  std::filesystem::create_directory_symlink(dir / "suite", dir / "suite" / "loop");
  const auto found = app::find_sequences(dir / "suite");
  ASSERT_EQ(found.size(), 1u);
  EXPECT_EQ(found[0].path, dir / "suite" / "teddy");
  EXPECT_EQ(found[0].name, "teddy") << "named by the link";
}

// Two generated sequences and a broken one, through the command: the table holds each run's
// own eval figures and their mean, the broken one is a failed row with its error, and a re-run
// skips what finished with the same settings.
TEST(CliBenchmark, TableMatchesEachRunsEvalAndAReRunContinues) {
  TempDir dir;
  write_sequence(dir / "suite" / "room_a", 6);
  write_sequence(dir / "suite" / "more" / "room_b", 8);
  std::filesystem::create_directories(dir / "suite" / "broken");
  std::ofstream(dir / "suite" / "broken" / "rgb.txt") << "0.0 rgb/missing.png\n";
  std::ofstream(dir / "suite" / "broken" / "depth.txt") << "0.0 depth/missing.png\n";
  std::ofstream(dir / "quick.json") << R"({"refine_passes": 1, "mapping": {"iterations": 3}})";
  const std::string command = "benchmark " + (dir / "suite").string() + " --out " + (dir / "bench").string() +
                              " --backend cpu --config " + (dir / "quick.json").string();
  const auto first = run_gslam(command);
  EXPECT_EQ(first.exit_code, 1) << "a failed sequence fails the benchmark: " << first.output;
  EXPECT_NE(first.output.find("1 of 3 sequences failed"), std::string::npos) << first.output;

  const nlohmann::json table = read_json(dir / "bench" / "benchmark.json");
  const auto& rows = table.at("sequences");
  ASSERT_EQ(rows.size(), 3u) << table.dump(2);
  EXPECT_EQ(rows[0].at("sequence"), "broken");
  EXPECT_EQ(rows[0].at("status"), "failed");
  EXPECT_NE(rows[0].at("error").get<std::string>().find("reconstruct: error: "), std::string::npos) << rows[0];
  double ate_sum = 0;
  for (std::size_t k : {1u, 2u}) {
    const std::string name = rows[k].at("sequence");
    EXPECT_EQ(rows[k].at("status"), "ok") << rows[k];
    const nlohmann::json eval = read_json(dir / "bench" / name / "eval.json");
    const nlohmann::json summary = read_json(dir / "bench" / name / "summary.json");
    EXPECT_DOUBLE_EQ(rows[k].at("ate_rmse_cm").get<double>(), 100 * eval.at("ate").at("rmse_m").get<double>()) << name;
    EXPECT_DOUBLE_EQ(rows[k].at("psnr_db").get<double>(), eval.at("rendering").at("psnr_db").get<double>()) << name;
    EXPECT_EQ(rows[k].at("frames"), summary.at("frames")) << name;
    EXPECT_GE(rows[k].at("fps_through").get<double>(), rows[k].at("fps_overall").get<double>()) << name;
    EXPECT_GT(rows[k].at("peak_memory_mib").get<double>(), 0) << name;
    EXPECT_TRUE(rows[k].at("baseline_opencv_ate_rmse_cm").is_number()) << "the baseline beside it: " << rows[k];
    ate_sum += rows[k].at("ate_rmse_cm").get<double>();
  }
  EXPECT_EQ(rows[1].at("sequence"), "more_room_b");
  EXPECT_EQ(rows[2].at("sequence"), "room_a");
  EXPECT_DOUBLE_EQ(table.at("mean").at("ate_rmse_cm").get<double>(), ate_sum / 2);
  EXPECT_EQ(table.at("mean").at("frames").get<int>(), 14);
  std::ifstream md(dir / "bench" / "benchmark.md");
  const std::string markdown((std::istreambuf_iterator<char>(md)), std::istreambuf_iterator<char>());
  EXPECT_NE(markdown.find("| room_a | 6 | "), std::string::npos) << markdown;
  EXPECT_NE(markdown.find("| broken | failed: reconstruct: error: "), std::string::npos) << markdown;
  EXPECT_NE(markdown.find("| **mean** | 14 | "), std::string::npos) << markdown;
  EXPECT_NE(first.output.find(markdown), std::string::npos) << "the table is printed too";

  const auto again = run_gslam(command);
  EXPECT_EQ(again.exit_code, 1);
  EXPECT_NE(again.output.find("room_a (" + (dir / "suite" / "room_a").string() + "): finished earlier"), std::string::npos)
      << again.output;
  EXPECT_NE(again.output.find("more_room_b (" + (dir / "suite" / "more" / "room_b").string() + "): finished earlier"),
            std::string::npos)
      << again.output;
  EXPECT_EQ(read_json(dir / "bench" / "benchmark.json").at("sequences"), rows) << "the same table";

  // Other settings run every sequence again.
  const auto other = run_gslam(command + " --max-frames 5");
  EXPECT_EQ(other.output.find("finished earlier"), std::string::npos) << other.output;
  EXPECT_EQ(read_json(dir / "bench" / "benchmark.json").at("mean").at("frames").get<int>(), 10);
}

// The baseline follows the generated camera: its motion from the first frame to the last is the
// truth's within a tenth (a wrong direction of OpenCV's Rt would reverse it).
TEST(OpenCvBaseline, FollowsTheGeneratedCamera) {
  TempDir dir;
  write_sequence(dir / "seq", 20);
  const app::Dataset d = app::open_dataset(dir / "seq");
  const app::BaselineTrajectory b = app::opencv_odometry_baseline(d);
  ASSERT_EQ(b.poses.size(), 20u);
  EXPECT_EQ(b.failures, 0u);
  const Eigen::Isometry3d truth = d.entries.front().T_world_cam_truth->inverse() * *d.entries.back().T_world_cam_truth;
  const Eigen::Isometry3d estimate = b.poses.front().T_world_cam.inverse() * b.poses.back().T_world_cam;
  ASSERT_GT(truth.translation().norm(), 0.05) << "the generated camera moves";
  EXPECT_LT((estimate.translation() - truth.translation()).norm(), 0.1 * truth.translation().norm())
      << "estimate " << estimate.translation().transpose() << ", truth " << truth.translation().transpose();
}

TEST(CliBenchmark, AFolderWithoutSequencesIsAnError) {
  TempDir dir;
  std::filesystem::create_directories(dir / "empty");
  const auto r = run_gslam("benchmark " + (dir / "empty").string() + " --out " + (dir / "bench").string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("no sequence found"), std::string::npos) << r.output;
}

}  // namespace
