// Reads a sequence's frames one ahead: while the caller works on one frame, the next one in
// `order` is read and decoded on a thread of its own, so reading overlaps tracking and mapping.
// The frames are exactly those load(i) gives; only when they are read changes.
#pragma once
#include <cstddef>
#include <functional>
#include <future>
#include <vector>

#include "splat/rgbd_frame.h"

namespace app {

class FramePrefetch {
 public:
  using Load = std::function<splat::RgbdFrame(std::size_t)>;
  // The frames will mostly be taken in `order` (frame indices); starts reading the first.
  FramePrefetch(Load load, std::vector<std::size_t> order);
  // Frames first .. end - 1, in turn.
  FramePrefetch(Load load, std::size_t first, std::size_t end);
  ~FramePrefetch();  // waits for a read in flight (one frame)
  FramePrefetch(const FramePrefetch&) = delete;
  FramePrefetch& operator=(const FramePrefetch&) = delete;

  // Frame i, waiting for it if it is the one being read, and starts reading the one after it in
  // `order`. Any other frame is read here, as load(i) would. Rethrows the read's error
  // (splat::Error naming the file).
  splat::RgbdFrame take(std::size_t i);

 private:
  void start(std::size_t position);  // reads order_[position], if there is one
  Load load_;
  std::vector<std::size_t> order_;
  std::size_t position_ = 0;  // of the frame being read, where ahead_ is valid
  std::future<splat::RgbdFrame> ahead_;
};

}  // namespace app
