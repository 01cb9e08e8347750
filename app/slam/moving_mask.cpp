#include "slam/moving_mask.h"

#include <string>

#include "slam/frame_tracker.h"
#include "splat/error.h"
#include "tracking/moving_regions.h"

namespace app {

std::size_t MovingMask::left_out() const {
  std::size_t n = 0;
  for (std::size_t k = 1; k < runs.size(); k += 2) n += runs[k];
  return n;
}

MovingMask MovingMask::arrivals(const std::vector<uint8_t>& labels, int width, int factor) {
  MovingMask mask;
  if (width <= 0 || labels.empty() || labels.size() % static_cast<std::size_t>(width) != 0) return mask;
  bool any = false, current = false;
  uint32_t run = 0;
  for (uint8_t label : labels) {
    const bool out = label == tracking::kArrived || label == tracking::kOutline;
    any = any || out;
    if (out != current) {
      mask.runs.push_back(run);
      run = 0;
      current = out;
    }
    ++run;
  }
  if (!any) return {};
  mask.runs.push_back(run);
  mask.width = width;
  mask.height = static_cast<int>(labels.size() / static_cast<std::size_t>(width));
  mask.factor = factor;
  return mask;
}

void MovingMask::apply(splat::RgbdFrame& frame) const {
  if (empty()) return;
  if (frame.width() / factor != width || frame.height() / factor != height) {
    throw splat::Error("moving mask of " + std::to_string(width) + "x" + std::to_string(height) + " at 1/" +
                       std::to_string(factor) + " does not fit a " + std::to_string(frame.width()) + "x" +
                       std::to_string(frame.height()) + " frame");
  }
  std::vector<uint8_t> labels;
  labels.reserve(static_cast<std::size_t>(width) * height);
  for (std::size_t k = 0; k < runs.size(); ++k) labels.insert(labels.end(), runs[k], k % 2 ? 1 : 0);
  labels.resize(static_cast<std::size_t>(width) * height, 0);
  const std::vector<uint8_t> spread = upsample_labels(labels, width, factor, frame.width(), frame.height());
  if (frame.ignore.empty()) frame.ignore.assign(spread.size(), 0);
  for (std::size_t i = 0; i < spread.size(); ++i) frame.ignore[i] |= spread[i];
}

}  // namespace app
