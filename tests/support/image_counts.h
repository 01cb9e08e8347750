// Pixel counts for tests that look at a composed picture or a screenshot.
#pragma once
#include <algorithm>
#include <cstdint>

#include "splat/image.h"

namespace gslam::test {

// Pixels of columns [0, columns) with exactly this colour (columns < 0: every column).
inline int count_colour(const splat::Image8& image, const uint8_t rgb[3], int columns = -1) {
  const int w = columns < 0 ? image.width : std::min(columns, image.width);
  int n = 0;
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < w; ++x) {
      n += image.at(x, y, 0) == rgb[0] && image.at(x, y, 1) == rgb[1] && image.at(x, y, 2) == rgb[2];
    }
  }
  return n;
}

// Pixels of columns [0, columns) brighter than the viewers' dark background (channel sum > 120):
// the splats.
inline int count_map_pixels(const splat::Image8& image, int columns = -1) {
  const int w = columns < 0 ? image.width : std::min(columns, image.width);
  int n = 0;
  for (int y = 0; y < image.height; ++y) {
    for (int x = 0; x < w; ++x) n += image.at(x, y, 0) + image.at(x, y, 1) + image.at(x, y, 2) > 120;
  }
  return n;
}

}  // namespace gslam::test
