// SLAM for frames as they arrive: tracking on the caller's thread against the latest published
// map, mapping on a thread of its own. Keyframes wait in a one-slot queue: if mapping is still
// busy when a newer keyframe comes, the waiting one is skipped (counted), so tracking never
// waits for mapping and memory stays bounded.
#pragma once
#include <condition_variable>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "app/slam.h"

namespace app {

class LiveSlam {
 public:
  // The two rasterizers must differ (each thread renders with its own).
  LiveSlam(splat::Rasterizer& tracking_rasterizer, splat::Rasterizer& mapping_rasterizer,
           const SlamConfig& config);
  ~LiveSlam();
  LiveSlam(const LiveSlam&) = delete;
  LiveSlam& operator=(const LiveSlam&) = delete;

  // Tracks the frame (the first one seeds the map, synchronously) and hands keyframes to the
  // mapping thread. Rethrows an error the mapping thread hit.
  FrameRecord process(const splat::RgbdFrame& frame);
  // The map as last published by the mapping thread (never null after the first frame).
  std::shared_ptr<const splat::Gaussians> map() const;
  // Waits for the queued keyframe, if any, to be mapped, then stops the mapping thread.
  void finish();

  std::size_t keyframes_mapped() const;
  std::size_t keyframes_skipped() const;

 private:
  struct Pending {
    splat::RgbdFrame frame;
    Eigen::Isometry3d T_cam_world;
  };
  void mapping_loop();
  void publish();

  FrameTracker tracker_;
  mapping::Mapper mapper_;  // the mapping thread's alone once it runs
  mutable std::mutex mutex_;
  std::condition_variable wake_, idle_;
  std::optional<Pending> pending_;
  bool busy_ = false, stop_ = false;
  std::size_t mapped_ = 0, skipped_ = 0;
  std::shared_ptr<const splat::Gaussians> map_;
  std::exception_ptr error_;
  std::thread thread_;
};

}  // namespace app
