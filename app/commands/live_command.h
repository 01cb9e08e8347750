#pragma once
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "commands/backend.h"
#include "datasets/dataset.h"
#include "datasets/frame_source.h"
#include "slam/slam_config.h"
#include "slam/slam_system.h"

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

// What a host asks of a live run between two frames: the run folder written now (as the
// viewer's snapshot key), or the map and trajectory forgotten so that the next frame starts anew.
struct LiveRequest {
  enum Kind { kSave, kReset } kind;
  std::function<void(bool ok, const std::string& message)> answer;  // called once it is done
};

// A program that runs `gslam live` around frames of its own (the ROS node): the run takes its
// frames from open_source(), hands each tracked frame back, and serves its requests between
// frames. No window; the source and the options' `out` say the rest.
class LiveHost {
 public:
  virtual ~LiveHost() = default;
  virtual std::unique_ptr<FrameSource> open_source() = 0;
  // summary.json "input" (what eval and render read), written once the camera is known.
  virtual nlohmann::json input_json(const splat::Camera& intrinsics, const SlamConfig& config) const = 0;
  // After each frame, on the run's thread (the next frame waits for it).
  virtual void tracked(const splat::Camera& camera, const FrameRecord& record,
                       const SlamSystem& system) = 0;
  // Mapping went on while no frame came (it maps the keyframes it was given after the camera
  // stops): the map as it is now, on the run's thread; null after a reset.
  virtual void map_changed(std::shared_ptr<const splat::Gaussians> map) = 0;
  virtual std::optional<LiveRequest> next_request() = 0;
};

// run_live with `config` instead of options.config, and frames from `host` when it is given.
int run_live(const LiveOptions& options, const SlamConfig& config, LiveHost* host);

}  // namespace app
