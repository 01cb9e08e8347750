#include "slam/frame_prefetch.h"

#include <numeric>
#include <utility>

namespace app {

FramePrefetch::FramePrefetch(Load load, std::vector<std::size_t> order) : load_(std::move(load)), order_(std::move(order)) {
  start(0);
}

FramePrefetch::FramePrefetch(Load load, std::size_t first, std::size_t end)
    : FramePrefetch(std::move(load), [&] {
        std::vector<std::size_t> order(end > first ? end - first : 0);
        std::iota(order.begin(), order.end(), first);
        return order;
      }()) {}

FramePrefetch::~FramePrefetch() {
  if (ahead_.valid()) ahead_.wait();
}

void FramePrefetch::start(std::size_t position) {
  if (position >= order_.size()) return;
  position_ = position;
  ahead_ = std::async(std::launch::async, load_, order_[position]);
}

splat::RgbdFrame FramePrefetch::take(std::size_t i) {
  if (!ahead_.valid() || order_[position_] != i) return load_(i);  // the read ahead stays for its turn
  // get() leaves the future empty, so an error is thrown once, and no read is left running.
  const std::size_t next = position_ + 1;
  splat::RgbdFrame frame = ahead_.get();
  start(next);
  return frame;
}

}  // namespace app
