#pragma once
#include <cstdint>
#include <vector>

namespace splat {

// An image as a flat [H, W, C] row-major array.
template <typename T>
struct ImageT {
  int width = 0, height = 0, channels = 0;
  std::vector<T> data;

  ImageT() = default;
  ImageT(int w, int h, int c, T fill = T(0))
      : width(w), height(h), channels(c), data(static_cast<std::size_t>(w) * h * c, fill) {}
  std::size_t pixels() const { return static_cast<std::size_t>(width) * height; }
  T& at(int x, int y, int c = 0) { return data[(static_cast<std::size_t>(y) * width + x) * channels + c]; }
  const T& at(int x, int y, int c = 0) const {
    return data[(static_cast<std::size_t>(y) * width + x) * channels + c];
  }
};
using Image = ImageT<float>;
using Image8 = ImageT<uint8_t>;
using Image16 = ImageT<uint16_t>;

}  // namespace splat
