#include "datasets/frame_prefetch.h"

#include <utility>

namespace app {

FramePrefetch::FramePrefetch(Load load, std::size_t first, std::size_t end) : load_(std::move(load)), end_(end) {
  start(first);
}

FramePrefetch::~FramePrefetch() {
  if (ahead_future_.valid()) ahead_future_.wait();
}

void FramePrefetch::start(std::size_t i) {
  if (i >= end_) return;
  ahead_ = i;
  ahead_future_ = std::async(std::launch::async, load_, i);
}

splat::RgbdFrame FramePrefetch::take(std::size_t i) {
  if (!ahead_future_.valid() || ahead_ != i) {
    if (ahead_future_.valid()) ahead_future_.wait();  // a read of another frame: let it end unused
    ahead_future_ = {};
    splat::RgbdFrame frame = load_(i);
    start(i + 1);
    return frame;
  }
  // get() leaves the future empty, so an error is thrown once, and no read is left running.
  splat::RgbdFrame frame = ahead_future_.get();
  start(i + 1);
  return frame;
}

}  // namespace app
