#pragma once
#include <array>
#include <string>
#include <vector>

#include "splat/image.h"

namespace app {

// A minimal line plot rendered into an RGB image: axes scaled to the data with a margin,
// polylines in given colours, a frame. Enough for trajectories and error curves.
class LinePlot {
 public:
  LinePlot(int width, int height);
  // Adds a polyline (x[i], y[i]) in an RGB colour.
  void add(const std::vector<double>& x, const std::vector<double>& y, std::array<uint8_t, 3> color);
  // Keeps one unit the same length on both axes (for top views).
  void equal_axes(bool equal) { equal_ = equal; }
  splat::Image8 render() const;

 private:
  struct Series {
    std::vector<double> x, y;
    std::array<uint8_t, 3> color;
  };
  int width_, height_;
  bool equal_ = false;
  std::vector<Series> series_;
};

}  // namespace app
