#include "slam/frame_prefetch.h"

#include <numeric>
#include <utility>

namespace app {

FramePrefetch::FramePrefetch(Load load, std::vector<std::size_t> order) : load_(std::move(load)), order_(std::move(order)) {
  fill();
}

FramePrefetch::FramePrefetch(Load load, std::size_t first, std::size_t end)
    : FramePrefetch(std::move(load), [&] {
        std::vector<std::size_t> order(end > first ? end - first : 0);
        std::iota(order.begin(), order.end(), first);
        return order;
      }()) {}

FramePrefetch::~FramePrefetch() {
  for (std::future<splat::RgbdFrame>& read : ahead_) read.wait();
}

void FramePrefetch::fill() {
  while (ahead_.size() < kAhead && position_ + ahead_.size() < order_.size()) {
    ahead_.push_back(std::async(std::launch::async, load_, order_[position_ + ahead_.size()]));
  }
}

splat::RgbdFrame FramePrefetch::take(std::size_t i) {
  if (ahead_.empty() || order_[position_] != i)
    return load_(i);  // the reads ahead stay for their turn
  // Taken out before get(), so an error is thrown once and the reads after it go on.
  std::future<splat::RgbdFrame> read = std::move(ahead_.front());
  ahead_.pop_front();
  ++position_;
  fill();
  return read.get();
}

}  // namespace app
