// Where `gslam live` gets its frames: a recorded dataset replayed at its own frame rate, or a
// folder a camera driver writes into. Both deliver the newest frame only: a frame that arrives
// while the previous one is still waiting is dropped and counted, as a live camera drops them.
#pragma once
#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "datasets/dataset.h"
#include "splat/rgbd_frame.h"

namespace app {

struct ArrivedFrame {
  splat::RgbdFrame frame;
  std::chrono::steady_clock::time_point arrived;  // when the source made it available
  std::optional<Eigen::Isometry3d> T_world_cam_truth;
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  // The newest frame not yet taken, waiting up to `timeout`; nullopt if none came in time.
  virtual std::optional<ArrivedFrame> next(std::chrono::milliseconds timeout) = 0;
  // True once no frame will come any more (end of the recording, END file, idle timeout).
  virtual bool finished() const = 0;
  // Stops taking frames from the camera or recording (at the end of a run): delivered() and
  // dropped() keep their values from then on.
  virtual void stop() = 0;
  virtual std::size_t delivered() const = 0;  // frames handed out by next()
  virtual std::size_t dropped() const = 0;    // frames replaced before anyone took them
  virtual const splat::Camera& intrinsics() const = 0;
  // Where the camera's lens distorts: what turns its raw frames into intrinsics() ones.
  virtual std::shared_ptr<const Undistortion> undistortion() const { return nullptr; }
  virtual std::string describe() const = 0;
};

// Replays dataset frames at their recorded timestamps (speed 2 = twice as fast) from a thread
// of its own; frames whose time has passed before they could be loaded are dropped. Speed
// kEveryFrame replays every frame, each once the previous one has been taken, with no clock:
// none is dropped, however slow the consumer (tests, slow machines).
inline constexpr double kEveryFrame = 0;
std::unique_ptr<FrameSource> make_replay_source(Dataset dataset, double speed);

struct WatchOptions {
  // "fx,fy,cx,cy[,k1,k2,p1,p2,k3]"; empty: DIR/intrinsics.txt ("fx fy cx cy [k1 k2 p1 p2 k3]")
  std::string intrinsics;
  double depth_scale = 5000;  // stored value per metre
  // The colour camera where colour is not registered to depth, "fx,fy,cx,cy" (--color-camera);
  // anything else loads colour as it is: a stream has no frames yet to estimate it from.
  std::string color_camera;
  double idle_timeout = 10;   // seconds without a new frame before the stream counts as ended
  bool every_frame = false;   // each frame waits until the previous one is taken: none dropped
};

// Watches DIR/rgb/NAME.png + DIR/depth/NAME.png pairs appear (written atomically by the driver:
// to a temporary name, then renamed), in name order; NAME is the timestamp in seconds. The
// stream ends when DIR/END exists or after options.idle_timeout seconds without a new pair.
std::unique_ptr<FrameSource> make_watch_source(const std::filesystem::path& dir,
                                               const WatchOptions& options);

}  // namespace app
