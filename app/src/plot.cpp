#include "app/plot.h"

#include <algorithm>
#include <cmath>

namespace app {

LinePlot::LinePlot(int width, int height) : width_(width), height_(height) {}

void LinePlot::add(const std::vector<double>& x, const std::vector<double>& y, std::array<uint8_t, 3> color) {
  series_.push_back({x, y, color});
}

splat::Image8 LinePlot::render() const {
  splat::Image8 img(width_, height_, 3, 255);
  double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
  for (const auto& s : series_)
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      x0 = std::min(x0, s.x[i]), x1 = std::max(x1, s.x[i]);
      y0 = std::min(y0, s.y[i]), y1 = std::max(y1, s.y[i]);
    }
  if (!(x1 > x0)) x0 -= 1, x1 += 1;
  if (!(y1 > y0)) y0 -= 1, y1 += 1;
  const int margin = 24;
  double sx = (width_ - 2 * margin) / (x1 - x0), sy = (height_ - 2 * margin) / (y1 - y0);
  if (equal_) sx = sy = std::min(sx, sy);
  auto px = [&](double x) { return margin + (x - x0) * sx; };
  auto py = [&](double y) { return height_ - margin - (y - y0) * sy; };
  auto dot = [&](int x, int y, const std::array<uint8_t, 3>& c) {
    for (int dy = 0; dy < 2; ++dy)
      for (int dx = 0; dx < 2; ++dx) {
        const int xx = x + dx, yy = y + dy;
        if (xx >= 0 && yy >= 0 && xx < width_ && yy < height_)
          for (int k = 0; k < 3; ++k) img.at(xx, yy, k) = c[static_cast<std::size_t>(k)];
      }
  };
  auto line = [&](double ax, double ay, double bx, double by, const std::array<uint8_t, 3>& c) {
    const int steps = static_cast<int>(std::max(std::abs(bx - ax), std::abs(by - ay))) + 1;
    for (int i = 0; i <= steps; ++i) {
      const double t = static_cast<double>(i) / steps;
      dot(static_cast<int>(ax + t * (bx - ax)), static_cast<int>(ay + t * (by - ay)), c);
    }
  };
  const std::array<uint8_t, 3> grey = {160, 160, 160};
  line(margin, height_ - margin, width_ - margin, height_ - margin, grey);
  line(margin, margin, margin, height_ - margin, grey);
  for (const auto& s : series_)
    for (std::size_t i = 1; i < s.x.size(); ++i) line(px(s.x[i - 1]), py(s.y[i - 1]), px(s.x[i]), py(s.y[i]), s.color);
  return img;
}

}  // namespace app
