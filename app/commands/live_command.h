#pragma once
#include <filesystem>
#include <string>

#include "commands/backend.h"
#include "datasets/dataset.h"
#include "datasets/frame_source.h"

namespace app {

struct LiveOptions {
  std::filesystem::path
      source;  // dataset folder to replay; with `watch`, the folder a driver writes
  std::filesystem::path out;
  bool watch = false;
  WatchOptions watch_options;
  DatasetOptions dataset_options;  // replay: intrinsics, depth scale, max frames
  double speed = 1;                // replay rate relative to the recording
  bool headless = false;
  bool overwrite = false;          // replace another run's outputs in `out`
  double checkpoint_seconds = 30;  // outputs rewritten (atomically) this often
  std::filesystem::path config;    // optional SLAM settings (as reconstruct)
  BackendChoice backend;
  std::filesystem::path screenshot;  // save the window to this PNG once, then go on
  int screenshot_after = 1;          // frames tracked before that screenshot (or the end)
};

// `gslam live`: tracking on every frame it takes from the source, mapping on keyframes in a
// thread of its own, a viewer window unless headless. On the end of the stream, q in the
// window, or Ctrl-C, writes the same outputs as `gslam reconstruct` (RunOutputs) plus live
// figures in summary.json: frames dropped, tracking latency percentiles, keyframes skipped.
int run_live(const LiveOptions& options);

}  // namespace app
