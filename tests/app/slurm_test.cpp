// gslam benchmark and batch --slurm on a real one-node Slurm cluster started for these tests
// (support/slurm_cluster.h), against the same commands run locally; and the parsing of what
// sbatch and squeue print.
#include "batch/slurm.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <chrono>
#include <regex>
#include <thread>

#include "app/run_gslam.h"
#include "app/sequence_suite.h"
#include "support/slurm_cluster.h"
#include "support/temp_dir.h"

namespace {

using gslam::test::read_json;
using gslam::test::rows_without_timings;
using gslam::test::SlurmCluster;
using gslam::test::TempDir;

TEST(SlurmParsing, SbatchJobId) {
  EXPECT_EQ(app::parse_sbatch_job_id("Submitted batch job 1234\n"), "1234");
  EXPECT_EQ(app::parse_sbatch_job_id("sbatch: warning: no time limit\nSubmitted batch job 7\n"),
            "7");
  EXPECT_THROW(
      {
        try {
          app::parse_sbatch_job_id("sbatch: error: invalid partition specified: gpu\n");
        } catch (const std::exception& e) {
          EXPECT_NE(std::string(e.what()).find(
                        "no job id in its output: 'sbatch: error: invalid partition"),
                    std::string::npos)
              << e.what();
          throw;
        }
      },
      std::runtime_error);
}

TEST(SlurmParsing, SqueueProgressCountsTasksOfOneArray) {
  const std::string squeue =
      "12 [3-5,8] PENDING\n"  // not yet split by the scheduler: 4 tasks
      "12 1 RUNNING\n"
      "12 2 COMPLETING\n"
      "13 N/A PENDING\n"  // the merge job
      "99 0 RUNNING\n";   // someone else's array
  const app::ArrayProgress p = app::squeue_progress(squeue, "12", 10);
  EXPECT_EQ(p.pending, 4u);
  EXPECT_EQ(p.running, 2u);
  EXPECT_EQ(p.ended, 4u) << "tasks 0, 6, 7 and 9 have left the queue";
  EXPECT_EQ(app::squeue_progress("", "12", 3).ended, 3u) << "an empty queue: all ended";
  EXPECT_EQ(app::squeue_progress("12 [0-9%2] PENDING\n", "12", 10).pending, 10u)
      << "%2 limits, it is no index";
  EXPECT_TRUE(app::squeue_lists_job(squeue, "13"));
  EXPECT_FALSE(app::squeue_lists_job(squeue, "14"));
  EXPECT_FALSE(app::squeue_lists_job(squeue, "1")) << "whole ids only";
  EXPECT_THROW(app::squeue_progress("12 [x-y] PENDING\n", "12", 3), std::runtime_error);
}

TEST(SlurmParsing, SbatchCommandAndScriptQuoting) {
  app::SlurmOptions o;
  o.partition = "short";
  o.time_limit = "0:30:00";
  o.cpus_per_task = 4;
  const std::vector<std::string> array =
      app::sbatch_command(o, "gslam-benchmark", "/o/task.sh", "/o/logs/task-%a.log", 3);
  EXPECT_EQ(array, (std::vector<std::string>{"sbatch", "--job-name=gslam-benchmark",
                                             "--output=/o/logs/task-%a.log", "--array=0-2",
                                             "--partition=short", "--time=0:30:00",
                                             "--cpus-per-task=4", "/o/task.sh"}));
  const std::vector<std::string> merge =
      app::sbatch_command({}, "m", "/o/merge.sh", "/o/logs/merge.log", 0, "41");
  EXPECT_EQ(merge, (std::vector<std::string>{"sbatch", "--job-name=m", "--output=/o/logs/merge.log",
                                             "--dependency=afterany:41", "/o/merge.sh"}));
  EXPECT_EQ(app::shell_quote("/runs/it's here"), "'/runs/it'\\''s here'");
}

TEST(SlurmParsing, SlurmstepdErrorIsItsLastWordInTheLog) {
  TempDir dir;
  gslam::test::write_text(dir / "task.log",
                          "task 1: stuck\nslurmstepd-node7: error: *** JOB 12 ON node7 CANCELLED "
                          "AT 2026-11-25T15:30:02 ***\n"
                          "  stuck: interrupted: the same command resumes it\n");
  EXPECT_EQ(app::slurmstepd_error(dir / "task.log"),
            "slurmstepd-node7: error: *** JOB 12 ON node7 CANCELLED AT 2026-11-25T15:30:02 ***");
  gslam::test::write_text(dir / "clean.log", "task 0: fine\n");
  EXPECT_EQ(app::slurmstepd_error(dir / "clean.log"), "");
  EXPECT_EQ(app::slurmstepd_error(dir / "missing.log"), "");
}

// One cluster for all the tests below: starting it costs seconds.
class SlurmTest : public testing::Test {
 protected:
  static void SetUpTestSuite() { cluster_ = SlurmCluster::start(why_not_); }
  static void TearDownTestSuite() { cluster_.reset(); }
  void SetUp() override {
#ifdef GSLAM_REQUIRE_SLURM_TESTS
    if (!cluster_)
      GTEST_FAIL() << "no test Slurm cluster (GSLAM_REQUIRE_SLURM_TESTS): " << why_not_;
#endif
    if (!cluster_) GTEST_SKIP() << "no test Slurm cluster: " << why_not_;
  }

  static gslam::test::RunResult gslam(const std::string& args) {
    return cluster_->run(std::string(GSLAM_BINARY) + " " + args);
  }

  // Polls squeue until `line` is one of its lines ("%F %K %T": job, task, state).
  static bool wait_for_squeue_line(const std::string& line) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(5);
    while (std::chrono::steady_clock::now() < deadline) {
      if (("\n" + cluster_->run("squeue --noheader --array '--format=%F %K %T'").output)
              .find("\n" + line + "\n") != std::string::npos) {
        return true;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
    return false;
  }

  // Polls squeue until job `job` (any of its tasks) has left it.
  static bool wait_for_job_to_leave(const std::string& job) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::minutes(10);
    while (std::chrono::steady_clock::now() < deadline) {
      if (!app::squeue_lists_job(
              cluster_->run("squeue --noheader --array '--format=%F %K %T'").output, job))
        return true;
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
    }
    return false;
  }

  static std::string job_id(const std::string& output, const std::string& which) {
    std::smatch m;
    const std::regex pattern(which + " job (\\d+)");
    return std::regex_search(output, m, pattern) ? m[1].str() : "";
  }

  static inline std::unique_ptr<SlurmCluster> cluster_;
  static inline std::string why_not_;
};

// Three sequences and a broken one as a Slurm array job give the table a local run with --jobs 2
// gives (every figure but times and memory, and the broken one's error), and the command
// reports the jobs and their progress.
TEST_F(SlurmTest, BenchmarkTableEqualsALocalRunsTable) {
  TempDir dir;
  for (uint32_t k = 0; k < 3; ++k)
    gslam::test::write_tiny_sequence(dir / "suite" / ("room_" + std::to_string(k)), 5, k + 1);
  std::filesystem::create_directories(dir / "suite" / "broken");
  gslam::test::write_text(dir / "suite" / "broken" / "rgb.txt", "0.0 rgb/missing.png\n");
  gslam::test::write_text(dir / "suite" / "broken" / "depth.txt", "0.0 depth/missing.png\n");
  const std::string common = "benchmark " + (dir / "suite").string() +
                             " --backend cpu --threads 1 --config " +
                             gslam::test::write_quick_config(dir / "quick.json").string();
  const auto local = run_gslam(common + " --out " + (dir / "local").string() + " --jobs 2");
  EXPECT_EQ(local.exit_code, 1) << "broken fails: " << local.output;
  const auto slurm =
      gslam(common + " --out " + (dir / "slurm").string() + " --slurm --cpus-per-task 1");
  EXPECT_EQ(slurm.exit_code, 1) << "broken fails: " << slurm.output;
  EXPECT_NE(slurm.output.find("benchmark: 1 of 4 sequences failed"), std::string::npos)
      << slurm.output;

  EXPECT_NE(job_id(slurm.output, "array"), "") << slurm.output;
  EXPECT_NE(job_id(slurm.output, "merge"), "") << slurm.output;
  EXPECT_NE(slurm.output.find("4 of 4 ended"), std::string::npos) << slurm.output;
  const nlohmann::json local_table = read_json(dir / "local" / "benchmark.json");
  const nlohmann::json slurm_table = read_json(dir / "slurm" / "benchmark.json");
  ASSERT_EQ(local_table.at("sequences").size(), 4u) << local_table.dump(2);
  const auto& rows = slurm_table.at("sequences");
  ASSERT_EQ(rows.size(), 4u) << slurm_table.dump(2);
  EXPECT_EQ(rows[0].at("status"), "failed") << rows[0];
  EXPECT_NE(rows[0].at("error").get<std::string>().find("reconstruct: error: "), std::string::npos)
      << rows[0];
  for (std::size_t k = 1; k < rows.size(); ++k) EXPECT_EQ(rows[k].at("status"), "ok") << rows[k];
  EXPECT_EQ(rows_without_timings(slurm_table), rows_without_timings(local_table))
      << "slurm:\n"
      << slurm_table.dump(2) << "\nlocal:\n"
      << local_table.dump(2);
  EXPECT_NE(slurm.output.find(gslam::test::read_text(dir / "slurm" / "benchmark.md")),
            std::string::npos)
      << "the merged table is printed: " << slurm.output;
}

// A task cancelled while it runs (its sequence's rgb.txt a FIFO nobody writes, so it waits) is a
// failed row with Slurm's word on it; a re-run submits that sequence alone and finishes it.
TEST_F(SlurmTest, ACancelledTaskIsAFailedRowAndAReRunFinishesIt) {
  TempDir dir;
  gslam::test::write_tiny_sequence(dir / "suite" / "good", 5);
  gslam::test::write_tiny_sequence(dir / "suite" / "stuck", 5, 2);
  std::filesystem::remove(dir / "suite" / "stuck" / "rgb.txt");
  ASSERT_EQ(::mkfifo((dir / "suite" / "stuck" / "rgb.txt").c_str(), 0644), 0);
  const std::string command = "benchmark " + (dir / "suite").string() + " --out " +
                              (dir / "out").string() +
                              " --backend cpu --threads 1 --no-baseline --slurm --config " +
                              gslam::test::write_quick_config(dir / "quick.json").string();
  const auto submitted = gslam(command + " --no-wait");
  ASSERT_EQ(submitted.exit_code, 0) << submitted.output;
  const std::string array = job_id(submitted.output, "array"),
                    merge = job_id(submitted.output, "merge");
  ASSERT_NE(array, "") << submitted.output;
  ASSERT_NE(merge, "") << submitted.output;
  const auto meanwhile = gslam(command + " --no-wait");  // stuck keeps the array in the queue
  EXPECT_EQ(meanwhile.exit_code, 1);
  EXPECT_NE(meanwhile.output.find("jobs " + array + " and " + merge +
                                  " of an earlier --slurm run are still in squeue"),
            std::string::npos)
      << meanwhile.output;

  ASSERT_TRUE(wait_for_squeue_line(array + " 1 RUNNING")) << "task 1 (stuck) never ran";
  EXPECT_EQ(cluster_->run("scancel " + array + "_1").exit_code, 0);
  ASSERT_TRUE(wait_for_job_to_leave(merge)) << "the merge job never ended";
  const nlohmann::json table = read_json(dir / "out" / "benchmark.json");
  ASSERT_EQ(table.at("sequences").size(), 2u) << table.dump(2);
  const auto& good = table.at("sequences")[0];
  const auto& stuck = table.at("sequences")[1];
  EXPECT_EQ(good.at("status"), "ok") << good;
  EXPECT_EQ(stuck.at("status"), "failed") << stuck;
  EXPECT_TRUE(
      std::regex_search(stuck.at("error").get<std::string>(), std::regex("slurmstepd.*CANCELLED")))
      << "the task log's last word from Slurm: " << stuck;

  std::filesystem::remove_all(dir / "suite" / "stuck");
  gslam::test::write_tiny_sequence(dir / "suite" / "stuck", 5, 2);
  const auto again = gslam(command);
  ASSERT_EQ(again.exit_code, 0) << again.output;
  EXPECT_NE(again.output.find("good (" + (dir / "suite" / "good").string() + "): finished earlier"),
            std::string::npos)
      << again.output;
  EXPECT_NE(again.output.find("(1 tasks"), std::string::npos)
      << "only stuck is submitted: " << again.output;
  const nlohmann::json finished = read_json(dir / "out" / "benchmark.json");
  for (const auto& row : finished.at("sequences")) EXPECT_EQ(row.at("status"), "ok") << row;
  EXPECT_EQ(finished.at("sequences")[0], table.at("sequences")[0]) << "good was not run again";
}

// gslam batch through Slurm gives the table it gives locally.
TEST_F(SlurmTest, BatchTableEqualsALocalRunsTable) {
  TempDir dir;
  gslam::test::write_tiny_sequence(dir / "suite" / "a", 5, 3);
  gslam::test::write_tiny_sequence(dir / "suite" / "b", 6, 4);
  const std::string common = "batch " + (dir / "suite").string() +
                             " --backend cpu --threads 1 --config " +
                             gslam::test::write_quick_config(dir / "quick.json").string();
  const auto local = run_gslam(common + " --out " + (dir / "local").string());
  ASSERT_EQ(local.exit_code, 0) << local.output;
  const auto slurm = gslam(common + " --out " + (dir / "slurm").string() + " --slurm");
  ASSERT_EQ(slurm.exit_code, 0) << slurm.output;
  const nlohmann::json local_table = read_json(dir / "local" / "batch.json");
  ASSERT_EQ(local_table.at("sequences").size(), 2u) << local_table.dump(2);
  EXPECT_EQ(rows_without_timings(read_json(dir / "slurm" / "batch.json")),
            rows_without_timings(local_table));
}

}  // namespace
