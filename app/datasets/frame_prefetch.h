// Reads a sequence's frames one ahead: while the caller works on frame i, frame i + 1 is read
// and decoded on a thread of its own, so a run's loading overlaps its tracking and mapping.
// The frames are exactly those load(i) gives; only when they are read changes.
#pragma once
#include <cstddef>
#include <functional>
#include <future>

#include "splat/rgbd_frame.h"

namespace app {

class FramePrefetch {
 public:
  using Load = std::function<splat::RgbdFrame(std::size_t)>;
  // Frames first .. end - 1 will be taken in order; starts reading `first`.
  FramePrefetch(Load load, std::size_t first, std::size_t end);
  ~FramePrefetch();  // waits for a read in flight (one frame)
  FramePrefetch(const FramePrefetch&) = delete;
  FramePrefetch& operator=(const FramePrefetch&) = delete;

  // Frame i, waiting for it if it is still being read, and starts reading i + 1. Taken out of
  // order, i is read here. Rethrows the read's error (splat::Error naming the file).
  splat::RgbdFrame take(std::size_t i);

 private:
  void start(std::size_t i);
  Load load_;
  std::size_t end_;
  std::size_t ahead_ = 0;  // the frame being read, where ahead_future_ is valid
  std::future<splat::RgbdFrame> ahead_future_;
};

}  // namespace app
