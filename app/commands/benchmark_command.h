#pragma once
#include <filesystem>

#include "batch/slurm.h"
#include "commands/backend.h"

namespace app {

// What `gslam benchmark` and `gslam batch` run, and where.
struct BenchmarkOptions {
  bool evaluate = true;          // benchmark: reconstruct + eval; batch: reconstruct only
  std::filesystem::path root;    // a folder of sequences; batch: or a list file of them
  std::filesystem::path out;     // OUT/NAME: each sequence's run folder; OUT/logs/NAME.log
  std::filesystem::path config;  // SLAM settings, the same for every sequence
  int test_every = 0;            // held-out test views, as reconstruct --test-every
  int max_frames = 0;            // the first N frames of each sequence; 0: all
  bool baseline = true;          // OpenCV's RGB-D odometry too (batch/opencv_baseline.h)
  BackendChoice backend;         // for reconstruct and eval
  int jobs = 1;                  // locally: sequences run at once, each a child process
  bool slurm = false;            // one Slurm array job instead (commands/slurm_submit.h)
  SlurmOptions slurm_options;    // with slurm: partition, time limit, CPUs per task
  bool wait = true;              // with slurm: wait for the jobs and print the table
};

// `gslam benchmark`: runs `gslam reconstruct` and `gslam eval` on every sequence found under
// `root`, each as a child process into its own run folder under `out`, with the same settings
// for all (nothing per sequence but the camera its folder gives), and writes the table of their
// figures (batch/benchmark_table.h), with the ATE of OpenCV's RGB-D odometry on the same frames
// (OUT/baselines/NAME.txt and .json) beside gslam's, to OUT/benchmark.md and OUT/benchmark.json
// after each sequence, and to standard output at the end. `gslam batch` (evaluate false) runs
// reconstruct only, on sequences without ground truth too, into OUT/batch.md and .json
// (batch/batch_table.h). Sequences run one at a time, `jobs` at once, or as the tasks of one Slurm
// array job. A re-run continues: a sequence whose run finished with the same settings is not run
// again, and an interrupted one resumes. A sequence that fails is a row saying so (its log's last
// line) and the others go on; the exit code is then 1. Ctrl-C stops after the sequences running
// (which write what they did). Throws splat::Error.
int run_benchmark(const BenchmarkOptions& options);

// The hidden commands a job runs: task `task` of the plan in `out` (commands/run_plan.h), and
// the merge of every run folder into the table, which it prints. Return the exit code.
int run_benchmark_task(const std::filesystem::path& out, std::size_t task);
int run_benchmark_merge(const std::filesystem::path& out);

}  // namespace app
