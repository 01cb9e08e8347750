#include "mapping/depth_holes.h"

#include <algorithm>
#include <string>

#include "splat/error.h"

namespace mapping {
namespace {

bool measured(float z) { return z > 0; }  // false for NaN

// For each pixel of one line (start, start + step, ..., count of them), the nearest
// measurement before it in the line's direction, folded into `fill` with max.
void sweep(std::span<const float> depth, std::vector<float>& fill, std::size_t start, std::ptrdiff_t step, int count) {
  float last = 0;
  std::ptrdiff_t p = static_cast<std::ptrdiff_t>(start);
  for (int k = 0; k < count; ++k, p += step) {
    const float z = depth[static_cast<std::size_t>(p)];
    if (measured(z)) {
      last = z;
    } else {
      fill[static_cast<std::size_t>(p)] = std::max(fill[static_cast<std::size_t>(p)], last);
    }
  }
}

}  // namespace

std::vector<float> fill_depth_holes(std::span<const float> depth, int width, int height) {
  if (width < 0 || height < 0 || depth.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height)) {
    throw splat::Error("fill_depth_holes: " + std::to_string(depth.size()) + " values for a " + std::to_string(width) +
                       "x" + std::to_string(height) + " image");
  }
  std::vector<float> fill(depth.size(), 0.f);
  for (std::size_t p = 0; p < depth.size(); ++p) {
    if (measured(depth[p])) fill[p] = depth[p];
  }
  const std::size_t w = static_cast<std::size_t>(width);
  for (int y = 0; y < height; ++y) {
    const std::size_t row = static_cast<std::size_t>(y) * w;
    sweep(depth, fill, row, 1, width);
    sweep(depth, fill, row + w - 1, -1, width);
  }
  for (int x = 0; x < width; ++x) {
    const std::size_t column = static_cast<std::size_t>(x);
    sweep(depth, fill, column, static_cast<std::ptrdiff_t>(w), height);
    sweep(depth, fill, column + (static_cast<std::size_t>(height) - 1) * w, -static_cast<std::ptrdiff_t>(w), height);
  }
  return fill;
}

}  // namespace mapping
