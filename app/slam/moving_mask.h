// A frame's moving objects as mapping leaves them out: the pixels where something moving stands
// now (tracking::kArrived), run-length coded, since the final sweep keeps one per frame. Pixels
// where an object left (kLeft) stay in mapping: there the map should learn the scene behind.
#pragma once
#include <cstdint>
#include <vector>

#include "splat/rgbd_frame.h"

namespace app {

struct MovingMask {
  int width = 0, height = 0;  // the labels' size (tracking::moving_level())
  int factor = 1;             // the frame is this many times larger
  std::vector<uint32_t> runs;  // alternating run lengths of kept and left-out pixels, kept first
  bool empty() const { return runs.empty(); }
  std::size_t left_out() const;  // pixels at the labels' size

  // From tracking::MovingLabel labels (width x height = labels.size()); empty if none arrived.
  static MovingMask arrivals(const std::vector<uint8_t>& labels, int width, int factor);
  // Adds the left-out pixels to the frame's ignored ones (splat::RgbdFrame::ignore).
  // Throws splat::Error if the frame is not `factor` times the labels' size.
  void apply(splat::RgbdFrame& frame) const;
};

}  // namespace app
