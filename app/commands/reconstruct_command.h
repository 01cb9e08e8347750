#pragma once
#include <filesystem>
#include <string>

#include "commands/backend.h"
#include "datasets/dataset.h"

namespace app {

struct ReconstructOptions {
  std::filesystem::path dataset;  // empty: the bundled synthetic sequence (generated into OUT)
  std::filesystem::path out;
  std::filesystem::path config;   // optional JSON with SLAM settings (README)
  DatasetOptions dataset_options;
  BackendChoice backend;
  bool print_config = false;      // write the effective configuration as JSON and stop
  bool overwrite = false;         // replace another run's outputs in `out`
  bool resume = false;            // continue the interrupted run in `out` from its checkpoint
  int test_every = 0;             // every N-th frame is a held-out test view (run_input.h)
  int checkpoint_every = 10;      // frames between atomic trajectory/summary checkpoints;
                                  // map.ply is checkpointed every 5x that
};

// `gslam reconstruct`: runs SLAM over a sequence and writes DIR/trajectory.txt (TUM, one line
// per frame), DIR/map.ply, DIR/map.glb, DIR/keyframes/kf_NNNN.{png,exr} (the final map seen
// from each keyframe) and DIR/summary.json. Every file is written atomically and checkpointed
// while running, so an interrupted run leaves the last complete outputs, and DIR/checkpoint.bin
// (the SLAM state: removed once the run completes), from which --resume continues it.
int run_reconstruct(const ReconstructOptions& options);

}  // namespace app
