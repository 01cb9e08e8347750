#pragma once
#include <filesystem>

#include "commands/backend.h"
#include "datasets/dataset.h"

namespace app {

struct EvalOptions {
  std::filesystem::path run;      // a gslam reconstruct output directory
  std::filesystem::path dataset;  // the sequence it was run on; empty: the one summary.json names
  DatasetOptions dataset_options;
  bool sim3 = false;              // align with scale
  int every = 1;                  // render quality on every N-th frame
  BackendChoice backend;
};

// `gslam eval`: trajectory errors (ATE RMSE after Horn/Umeyama alignment, RPE over 1 s, TUM
// conventions) and rendering quality of RUN/map.ply at the estimated poses of the input frames
// (PSNR, SSIM and depth L1 over full images, plus PSNR over pixels with measured depth, the
// masked variant SplaTAM reports). Writes RUN/eval.json, RUN/trajectory_top.png and
// RUN/ate_over_time.png.
int run_eval(const EvalOptions& options);

}  // namespace app
