#pragma once
#include <filesystem>

#include "commands/backend.h"

namespace app {

struct BenchmarkOptions {
  std::filesystem::path root;    // a folder of sequences (batch/sequence_finder.h)
  std::filesystem::path out;     // OUT/NAME: each sequence's run folder; OUT/logs/NAME.log
  std::filesystem::path config;  // SLAM settings, the same for every sequence
  int test_every = 0;            // held-out test views, as reconstruct --test-every
  int max_frames = 0;            // the first N frames of each sequence; 0: all
  bool baseline = true;          // OpenCV's RGB-D odometry on each sequence too (batch/opencv_baseline.h)
  BackendChoice backend;
};

// `gslam benchmark`: runs `gslam reconstruct` and `gslam eval` on every sequence found under
// `root`, each as a child process into its own run folder under `out`, with the same settings
// for all (nothing per sequence but the camera its folder gives), and writes the table of their
// figures (batch/benchmark_table.h), with the ATE of OpenCV's RGB-D odometry on the same frames
// (OUT/baselines/NAME.txt and .json) beside gslam's, to OUT/benchmark.md and OUT/benchmark.json after each
// sequence, and to standard output at the end. A re-run continues: a sequence whose run finished
// with the same settings is not run again, and an interrupted one resumes. A sequence that
// fails is a row saying so (its log's last line) and the others go on; the exit code is then 1.
// Ctrl-C stops after the sequence running (which writes what it did). Throws splat::Error.
int run_benchmark(const BenchmarkOptions& options);

}  // namespace app
