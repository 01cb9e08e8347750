// gslam batch run locally (a list file, --jobs), and the errors of benchmark and batch options.
#include <gtest/gtest.h>

#include "app/run_gslam.h"
#include "app/sequence_suite.h"
#include "support/temp_dir.h"

namespace {

using gslam::test::read_json;
using gslam::test::TempDir;

// Two sequences named in a list file, two at once: one run folder each with reconstruct's
// outputs and no eval, rows with summary.json's figures, and a re-run that skips both.
TEST(CliBatch, ListFileWithTwoJobsAndAReRunSkipsThem) {
  TempDir dir;
  gslam::test::write_tiny_sequence(dir / "recordings" / "kitchen", 5, 1);
  gslam::test::write_tiny_sequence(dir / "recordings" / "hall", 6, 2);
  std::ofstream(dir / "recordings" / "list.txt") << "# tonight's recordings\nkitchen\n\n"
                                                 << (dir / "recordings" / "hall").string() << "\n";
  const std::string command = "batch " + (dir / "recordings" / "list.txt").string() + " --out " +
                              (dir / "out").string() + " --jobs 2 --backend cpu --config " +
                              gslam::test::write_quick_config(dir / "quick.json").string();
  const auto first = run_gslam(command);
  ASSERT_EQ(first.exit_code, 0) << first.output;

  const nlohmann::json table = read_json(dir / "out" / "batch.json");
  const auto& rows = table.at("sequences");
  ASSERT_EQ(rows.size(), 2u) << table.dump(2);
  std::size_t gaussians = 0;
  for (const auto& row : rows) {
    const std::string name = row.at("sequence");
    EXPECT_EQ(row.at("status"), "ok") << row;
    const nlohmann::json summary = read_json(dir / "out" / name / "summary.json");
    EXPECT_EQ(row.at("frames"), summary.at("frames")) << name;
    EXPECT_EQ(row.at("gaussians"), summary.at("gaussians")) << name;
    EXPECT_GT(row.at("gaussians").get<std::size_t>(), 0u) << name;
    EXPECT_FALSE(std::filesystem::exists(dir / "out" / name / "eval.json"))
        << "batch does not evaluate: " << name;
    gaussians += row.at("gaussians").get<std::size_t>();
  }
  EXPECT_EQ(rows[0].at("sequence"), "hall");
  EXPECT_EQ(rows[1].at("sequence"), "kitchen");
  EXPECT_EQ(table.at("total").at("frames").get<int>(), 11);
  EXPECT_EQ(table.at("total").at("gaussians").get<std::size_t>(), gaussians);
  const std::string markdown = gslam::test::read_text(dir / "out" / "batch.md");
  EXPECT_NE(markdown.find("| kitchen | 5 | "), std::string::npos) << markdown;
  EXPECT_NE(markdown.find("| **total** | 11 | "), std::string::npos) << markdown;
  EXPECT_NE(first.output.find(markdown), std::string::npos)
      << "the table is printed too: " << first.output;

  const auto again = run_gslam(command);
  EXPECT_EQ(again.exit_code, 0) << again.output;
  EXPECT_NE(again.output.find("kitchen (" + (dir / "recordings" / "kitchen").string() +
                              "): finished earlier"),
            std::string::npos)
      << again.output;
  EXPECT_NE(again.output.find("hall ("), std::string::npos) << again.output;
  EXPECT_EQ(again.output.find("started"), std::string::npos)
      << "nothing runs again: " << again.output;
}

TEST(CliBatch, AListNamingAFolderWithoutASequenceIsAnError) {
  TempDir dir;
  std::filesystem::create_directories(dir / "notes");
  std::ofstream(dir / "list.txt") << "notes\n";
  const auto r =
      run_gslam("batch " + (dir / "list.txt").string() + " --out " + (dir / "out").string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(
      r.output.find("list.txt line 1: " + (dir / "notes").string() + " is not a sequence folder"),
      std::string::npos)
      << r.output;
}

TEST(CliBenchmark, SlurmWithoutSbatchIsAOneLineError) {
  TempDir dir;
  const auto r = gslam::test::run_command("PATH=/nonexistent " + std::string(GSLAM_BINARY) +
                                          " benchmark " + dir.path().string() + " --out " +
                                          (dir / "out").string() + " --slurm");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_EQ(r.output,
            "error: --slurm: sbatch is not on PATH (install Slurm's client tools, or run without "
            "--slurm)\n");
}

TEST(CliBenchmark, SlurmOptionsNeedSlurmAndExcludeJobs) {
  TempDir dir;
  const std::string command = "batch " + dir.path().string() + " --out " + (dir / "out").string();
  for (const char* flags : {" --no-wait", " --partition debug", " --slurm --jobs 2"}) {
    const auto r = run_gslam(command + flags);
    EXPECT_NE(r.exit_code, 0) << flags;
    EXPECT_NE(r.output.find("error: gslam batch: "), std::string::npos)
        << flags << ": " << r.output;
  }
  const auto zero = run_gslam(command + " --jobs 0");
  EXPECT_NE(zero.output.find("--jobs"), std::string::npos) << zero.output;
}

}  // namespace
