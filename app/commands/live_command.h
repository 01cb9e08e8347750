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
  double speed = 1;                // replay rate relative to the recording; kEveryFrame: no clock
  bool headless = false;
  bool overwrite = false;          // replace another run's outputs in `out`
  bool catch_up = true;            // at the end, map the keyframes mapping skipped
  double checkpoint_seconds = 30;  // outputs rewritten (atomically) this often
  std::filesystem::path config;    // optional SLAM settings (as reconstruct)
  BackendChoice backend;
  std::filesystem::path screenshot;  // save the window to this PNG once, then go on
  int screenshot_after = 1;          // frames tracked before that screenshot (or the end)
};

// `gslam live`: tracking on every frame it takes from the source, mapping on keyframes in a
// thread of its own, a viewer window unless headless. On the end of the stream or q in the
// window, maps the keyframes mapping skipped (unless !catch_up; Ctrl-C ends that too), then
// writes the same run folder as `gslam reconstruct` (RunOutputs, with summary.json "input", so
// eval and render take it) plus live figures in summary.json "live": frames received and
// dropped (never tracked: replaced by a newer frame while tracking was busy, or arriving while
// paused), tracking latency percentiles, keyframes mapped, caught up and skipped.
int run_live(const LiveOptions& options);

}  // namespace app
