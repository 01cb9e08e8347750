#include "mapping/depth_edges.h"

#include <algorithm>
#include <string>

#include "splat/error.h"

namespace mapping {

std::vector<uint8_t> depth_edges(std::span<const float> depth, int width, int height, double jump, int radius) {
  if (width < 0 || height < 0 || depth.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height)) {
    throw splat::Error("depth_edges: " + std::to_string(depth.size()) + " values for a " + std::to_string(width) + "x" +
                       std::to_string(height) + " image");
  }
  if (!(jump > 0) || radius < 0) throw splat::Error("depth_edges: jump must be positive and radius >= 0");
  const auto at = [&](int x, int y) { return depth[static_cast<std::size_t>(y) * width + x]; };
  // An edge between two neighbours: one measured and the other not, or a jump in depth.
  const auto edge = [&](float a, float b) {
    const bool ma = a > 0, mb = b > 0;
    if (ma != mb) return true;
    return ma && std::abs(a - b) > jump * std::min(a, b);
  };
  std::vector<uint8_t> seeds(depth.size(), 0);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const bool right = x + 1 < width && edge(at(x, y), at(x + 1, y));
      const bool down = y + 1 < height && edge(at(x, y), at(x, y + 1));
      if (right) seeds[static_cast<std::size_t>(y) * width + x] = seeds[static_cast<std::size_t>(y) * width + x + 1] = 1;
      if (down) seeds[static_cast<std::size_t>(y) * width + x] = seeds[static_cast<std::size_t>(y + 1) * width + x] = 1;
    }
  }
  if (radius == 0) return seeds;
  // Dilation by a (2 radius + 1) square, separably: rows, then columns.
  std::vector<uint8_t> rows(depth.size(), 0), out(depth.size(), 0);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      if (!seeds[static_cast<std::size_t>(y) * width + x]) continue;
      for (int k = std::max(0, x - radius); k <= std::min(width - 1, x + radius); ++k) rows[static_cast<std::size_t>(y) * width + k] = 1;
    }
  }
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      if (!rows[static_cast<std::size_t>(y) * width + x]) continue;
      for (int k = std::max(0, y - radius); k <= std::min(height - 1, y + radius); ++k) out[static_cast<std::size_t>(k) * width + x] = 1;
    }
  }
  return out;
}

}  // namespace mapping
