// Reads a sequence's frames ahead: while the caller works on one frame, the next ones in `order`
// are read and decoded, each on a thread of its own, so reading overlaps tracking and mapping.
// Two at once: a caller that does little per frame (the sweep's carving) waits on decoding, and
// a PNG pair decodes on one core. The frames are exactly those load(i) gives; only when they are
// read changes.
#pragma once
#include <cstddef>
#include <deque>
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
  ~FramePrefetch();  // waits for the reads in flight
  FramePrefetch(const FramePrefetch&) = delete;
  FramePrefetch& operator=(const FramePrefetch&) = delete;

  // Frame i, waiting for it if it is the next one read ahead, and starts reading further in
  // `order`. Any other frame is read here, as load(i) would. Rethrows the read's error
  // (splat::Error naming the file).
  splat::RgbdFrame take(std::size_t i);

 private:
  static constexpr std::size_t kAhead = 2;  // reads in flight
  void fill();                              // starts reads up to kAhead in flight
  Load load_;
  std::vector<std::size_t> order_;
  std::size_t position_ = 0;  // in order_ of ahead_.front()
  // The reads of order_[position_], order_[position_ + 1], ...
  std::deque<std::future<splat::RgbdFrame>> ahead_;
};

}  // namespace app
