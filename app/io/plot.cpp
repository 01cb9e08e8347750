#include "io/plot.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include <stb/stb_easy_font.h>

namespace app {
namespace {

using Color = std::array<uint8_t, 3>;

void fill(splat::Image8& img, int x0, int y0, int x1, int y1, const Color& c) {
  for (int y = std::max(0, y0); y < std::min(img.height, y1); ++y)
    for (int x = std::max(0, x0); x < std::min(img.width, x1); ++x)
      for (int k = 0; k < 3; ++k) img.at(x, y, k) = c[static_cast<std::size_t>(k)];
}

// stb_easy_font builds each glyph from axis-aligned quads in font pixels; each is filled as a
// `scale` x `scale` block per font pixel.
constexpr int kTextScale = 2;
int text_width(const std::string& text) {
  return stb_easy_font_width(const_cast<char*>(text.c_str())) * kTextScale;
}
constexpr int kTextHeight = 7 * kTextScale;

void draw_text(splat::Image8& img, int x, int y, const std::string& text, const Color& c) {
  struct Vertex {
    float x, y, z;
    unsigned char color[4];
  };
  std::vector<Vertex> quads(text.size() * 64 + 64);
  const int count = stb_easy_font_print(0, 0, const_cast<char*>(text.c_str()), nullptr, quads.data(),
                                        static_cast<int>(quads.size() * sizeof(Vertex)));
  for (int q = 0; q < count; ++q) {
    const Vertex* v = &quads[static_cast<std::size_t>(q) * 4];
    const float qx0 = std::min(v[0].x, v[2].x), qx1 = std::max(v[0].x, v[2].x);
    const float qy0 = std::min(v[0].y, v[2].y), qy1 = std::max(v[0].y, v[2].y);
    fill(img, x + static_cast<int>(qx0 * kTextScale), y + static_cast<int>(qy0 * kTextScale),
         x + static_cast<int>(qx1 * kTextScale), y + static_cast<int>(qy1 * kTextScale), c);
  }
}

std::string format_tick(double v, double step) {
  char buf[32];
  const int decimals = std::clamp(static_cast<int>(std::ceil(-std::log10(step))), 0, 6);
  std::snprintf(buf, sizeof buf, "%.*f", decimals, std::abs(v) < step * 1e-6 ? 0.0 : v);
  return buf;
}

}  // namespace

std::vector<double> nice_ticks(double lo, double hi, int count) {
  if (!(hi > lo) || count < 1) return {lo};
  const double raw = (hi - lo) / count;
  const double power = std::pow(10.0, std::floor(std::log10(raw)));
  double step = power;
  for (const double m : {1.0, 2.0, 5.0, 10.0}) {
    step = m * power;
    if (step >= raw) break;
  }
  std::vector<double> ticks;  // integer multiples of the step, so no rounding accumulates
  const double first = std::ceil(lo / step - 1e-9), last = std::floor(hi / step + 1e-9);
  for (double k = first; k <= last; ++k) ticks.push_back(k * step);
  return ticks;
}

std::array<uint8_t, 3> scale_color(double t) {
  static constexpr double kStops[5][3] = {{40, 60, 220}, {0, 190, 220}, {40, 180, 60}, {235, 200, 0}, {220, 30, 30}};
  t = std::clamp(std::isfinite(t) ? t : 0.0, 0.0, 1.0) * 4;
  const int i = std::min(3, static_cast<int>(t));
  const double f = t - i;
  std::array<uint8_t, 3> c;
  for (int k = 0; k < 3; ++k) c[static_cast<std::size_t>(k)] = static_cast<uint8_t>(std::lround((1 - f) * kStops[i][k] + f * kStops[i + 1][k]));
  return c;
}

LinePlot::LinePlot(int width, int height) : width_(width), height_(height) {}

void LinePlot::add_coloured(const std::vector<double>& x, const std::vector<double>& y, const std::vector<double>& value,
                            std::string name) {
  series_.push_back({x, y, {0, 0, 0}, std::move(name), value});
}

void LinePlot::mark(double x, double y, std::array<uint8_t, 3> color, std::string label) {
  markers_.push_back({x, y, color, std::move(label)});
}

void LinePlot::add(const std::vector<double>& x, const std::vector<double>& y, std::array<uint8_t, 3> color,
                   std::string name) {
  series_.push_back({x, y, color, std::move(name), {}});
}

splat::Image8 LinePlot::render() const {
  splat::Image8 img(width_, height_, 3, 255);
  double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
  for (const auto& s : series_)
    for (std::size_t i = 0; i < s.x.size(); ++i) {
      x0 = std::min(x0, s.x[i]), x1 = std::max(x1, s.x[i]);
      y0 = std::min(y0, s.y[i]), y1 = std::max(y1, s.y[i]);
    }
  for (const auto& m : markers_) {
    x0 = std::min(x0, m.x), x1 = std::max(x1, m.x);
    y0 = std::min(y0, m.y), y1 = std::max(y1, m.y);
  }
  if (!(x1 > x0)) x0 -= 1, x1 += 1;
  if (!(y1 > y0)) y0 -= 1, y1 += 1;
  // A margin of 4% of the range on every side: no curve runs along the frame.
  const double mx = 0.04 * (x1 - x0), my = 0.04 * (y1 - y0);
  x0 -= mx, x1 += mx, y0 -= my, y1 += my;
  // Room for tick numbers and titles on the left and bottom.
  const int left = 80, right = 20, top = title_.empty() ? 24 : 44, bottom = 56;
  double sx = (width_ - left - right) / (x1 - x0), sy = (height_ - top - bottom) / (y1 - y0);
  if (equal_) sx = sy = std::min(sx, sy);
  auto px = [&](double x) { return left + (x - x0) * sx; };
  auto py = [&](double y) { return height_ - bottom - (y - y0) * sy; };
  // The axes span what is visible (with equal axes, more than the data on one side).
  const double x_end = x0 + (width_ - left - right) / sx, y_end = y0 + (height_ - top - bottom) / sy;
  const Color grey = {160, 160, 160}, light = {232, 232, 232}, black = {0, 0, 0};
  auto dot = [&](int x, int y, const Color& c) { fill(img, x, y, x + 2, y + 2, c); };
  auto line = [&](double ax, double ay, double bx, double by, const Color& c) {
    const int steps = static_cast<int>(std::max(std::abs(bx - ax), std::abs(by - ay))) + 1;
    for (int i = 0; i <= steps; ++i) {
      const double t = static_cast<double>(i) / steps;
      dot(static_cast<int>(ax + t * (bx - ax)), static_cast<int>(ay + t * (by - ay)), c);
    }
  };
  const std::vector<double> xt = nice_ticks(x0, x_end, 6), yt = nice_ticks(y0, y_end, 5);
  const double x_step = xt.size() > 1 ? xt[1] - xt[0] : 1, y_step = yt.size() > 1 ? yt[1] - yt[0] : 1;
  for (double t : xt) {
    line(px(t), top, px(t), height_ - bottom, light);
    const std::string s = format_tick(t, x_step);
    draw_text(img, static_cast<int>(px(t)) - text_width(s) / 2, height_ - bottom + 8, s, black);
  }
  for (double t : yt) {
    line(left, py(t), width_ - right, py(t), light);
    const std::string s = format_tick(t, y_step);
    draw_text(img, left - 8 - text_width(s), static_cast<int>(py(t)) - kTextHeight / 2, s, black);
  }
  line(left, height_ - bottom, width_ - right, height_ - bottom, grey);
  line(left, top, left, height_ - bottom, grey);
  for (const auto& s : series_) {
    double lo = INFINITY, hi = -INFINITY;
    for (double v : s.value) lo = std::min(lo, v), hi = std::max(hi, v);
    const double span = hi > lo ? hi - lo : 1;
    for (std::size_t i = 1; i < s.x.size(); ++i) {
      const Color c = s.value.empty() ? s.color : scale_color((0.5 * (s.value[i - 1] + s.value[i]) - lo) / span);
      line(px(s.x[i - 1]), py(s.y[i - 1]), px(s.x[i]), py(s.y[i]), c);
    }
  }
  for (const auto& m : markers_) {
    const int x = static_cast<int>(px(m.x)), y = static_cast<int>(py(m.y));
    fill(img, x - 6, y - 6, x + 7, y + 7, black);
    fill(img, x - 4, y - 4, x + 5, y + 5, m.color);
    draw_text(img, x + 10, y - kTextHeight / 2, m.label, black);
  }
  if (!x_label_.empty()) {
    draw_text(img, left + (width_ - left - right - text_width(x_label_)) / 2, height_ - bottom + 32, x_label_, black);
  }
  if (!y_label_.empty()) draw_text(img, 8, std::max(0, top - 16), y_label_, black);
  if (!title_.empty()) draw_text(img, left, 2, title_, black);
  // Legend, top right: a colour bar and the name of each named series; for a coloured one the
  // scale, its lowest and its highest value.
  int legend_y = top + 8;
  for (const auto& s : series_) {
    if (s.name.empty()) continue;
    if (!s.value.empty()) {
      double lo = INFINITY, hi = -INFINITY;
      for (double v : s.value) lo = std::min(lo, v), hi = std::max(hi, v);
      char range[64];
      std::snprintf(range, sizeof range, "%.3g", lo);
      const std::string low = range;
      std::snprintf(range, sizeof range, "%.3g", hi);
      const std::string high = range;
      const int bar = 100, x = width_ - right - text_width(high) - bar - text_width(low) - 16;
      draw_text(img, x, legend_y, low, black);
      for (int i = 0; i < bar; ++i) {
        fill(img, x + text_width(low) + 6 + i, legend_y, x + text_width(low) + 7 + i, legend_y + kTextHeight,
             scale_color(static_cast<double>(i) / (bar - 1)));
      }
      draw_text(img, x + text_width(low) + bar + 12, legend_y, high, black);
      legend_y += kTextHeight + 4;
      draw_text(img, width_ - right - text_width(s.name), legend_y, s.name, black);
      legend_y += kTextHeight + 8;
      continue;
    }
    const int x = width_ - right - text_width(s.name) - 32;
    fill(img, x, legend_y + kTextHeight / 2 - 2, x + 20, legend_y + kTextHeight / 2 + 2, s.color);
    draw_text(img, x + 26, legend_y, s.name, black);
    legend_y += kTextHeight + 8;
  }
  return img;
}

}  // namespace app
