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
constexpr int kTextHeight = 7 * kTextScale;  // capitals and digits
constexpr int kTextDepth = 10 * kTextScale;  // with descenders (g, p, y)
constexpr int kTextInset = 2;                // text keeps this far from the image's edges
constexpr int kLineWidth = 2;                // single-colour series, pixels
constexpr int kColouredWidth = 5;  // series coloured by value: wide enough to read the colour
constexpr int kColourBar = 100;    // colour bar length in the legend, pixels

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

namespace {

// Integer multiples of `step` within [lo, hi] (so no rounding accumulates).
std::vector<double> ticks_with_step(double lo, double hi, double step) {
  std::vector<double> ticks;
  const double first = std::ceil(lo / step - 1e-9), last = std::floor(hi / step + 1e-9);
  for (double k = first; k <= last; ++k) ticks.push_back(k * step);
  return ticks;
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
  return ticks_with_step(lo, hi, step);
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
  if (!(x1 >= x0)) x0 = 0, x1 = 0;  // nothing to plot
  if (!(y1 >= y0)) y0 = 0, y1 = 0;
  if (equal_) {
    // A flat path (a line along one axis) still gets a square of the other one's size.
    const double span = std::max(x1 - x0, y1 - y0) > 0 ? std::max(x1 - x0, y1 - y0) : 2.0;
    if (!(x1 > x0)) x0 -= 0.5 * span, x1 += 0.5 * span;
    if (!(y1 > y0)) y0 -= 0.5 * span, y1 += 0.5 * span;
  }
  if (!(x1 > x0)) x0 -= 1, x1 += 1;
  if (!(y1 > y0)) y0 -= 1, y1 += 1;
  // A margin of 4% of the range on every side (of the larger range with equal axes, so the
  // margin is the same length on both): no curve runs along the frame.
  const double mx = 0.04 * (equal_ ? std::max(x1 - x0, y1 - y0) : x1 - x0);
  const double my = 0.04 * (equal_ ? std::max(x1 - x0, y1 - y0) : y1 - y0);
  x0 -= mx, x1 += mx, y0 -= my, y1 += my;

  // The legend goes in a band above the plot area, so it never hides data: named series left to
  // right, wrapping to a new row when the width is used up.
  const Color grey = {160, 160, 160}, light = {232, 232, 232}, black = {0, 0, 0};
  const int left = 80, right = 20, bottom = 56, row = kTextHeight + 8;
  struct LegendItem {
    const Series* series;
    int x, y, width;
    std::string low, high;  // a coloured series' range
  };
  std::vector<LegendItem> legend;
  int legend_x = left, legend_y = title_.empty() ? 6 : 24;
  bool any_legend = false;
  for (const auto& s : series_) {
    if (s.name.empty()) continue;
    LegendItem item{&s, 0, 0, 26 + text_width(s.name), {}, {}};
    if (!s.value.empty()) {
      double lo = INFINITY, hi = -INFINITY;
      for (double v : s.value) lo = std::min(lo, v), hi = std::max(hi, v);
      char range[64];
      std::snprintf(range, sizeof range, "%.3g", lo);
      item.low = range;
      std::snprintf(range, sizeof range, "%.3g", hi);
      item.high = range;
      item.width = text_width(item.low) + 6 + kColourBar + 6 + text_width(item.high) + 10 +
                   text_width(s.name);
    }
    if (legend_x > left && legend_x + item.width > width_ - right) legend_x = left, legend_y += row;
    item.x = legend_x, item.y = legend_y;
    legend_x += item.width + 24;
    legend.push_back(item);
    any_legend = true;
  }
  // Room for tick numbers and titles on the left and bottom; the title, the legend and the y
  // axis title on top.
  const int top = any_legend ? legend_y + row + 20 : (title_.empty() ? 24 : 44);
  const int plot_w = std::max(1, width_ - left - right),
            plot_h = std::max(1, height_ - top - bottom);
  double sx = plot_w / (x1 - x0), sy = plot_h / (y1 - y0);
  if (equal_) {
    // The same metres per pixel on both axes; the data centred, the shorter range widened.
    sx = sy = std::min(sx, sy);
    const double cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1);
    x0 = cx - 0.5 * plot_w / sx, x1 = cx + 0.5 * plot_w / sx;
    y0 = cy - 0.5 * plot_h / sy, y1 = cy + 0.5 * plot_h / sy;
  }
  auto px = [&](double x) { return left + (x - x0) * sx; };
  auto py = [&](double y) { return height_ - bottom - (y - y0) * sy; };
  // Text is placed whole inside the image: a label that would cross an edge is moved in.
  auto text = [&](int x, int y, const std::string& s, const Color& c) {
    x = std::clamp(x, kTextInset, std::max(kTextInset, width_ - kTextInset - text_width(s)));
    y = std::clamp(y, kTextInset, std::max(kTextInset, height_ - kTextInset - kTextDepth));
    draw_text(img, x, y, s, c);
  };
  auto line = [&](double ax, double ay, double bx, double by, const Color& c, int thickness) {
    const int steps = static_cast<int>(std::max(std::abs(bx - ax), std::abs(by - ay))) + 1;
    const int lo = -(thickness - 1) / 2, hi = lo + thickness;
    for (int i = 0; i <= steps; ++i) {
      const double t = static_cast<double>(i) / steps;
      const int x = static_cast<int>(ax + t * (bx - ax)), y = static_cast<int>(ay + t * (by - ay));
      fill(img, x + lo, y + lo, x + hi, y + hi, c);
    }
  };
  std::vector<double> xt = nice_ticks(x0, x1, 6), yt = nice_ticks(y0, y1, 5);
  if (equal_ && xt.size() > 1 && yt.size() > 1) {
    // One grid spacing on both axes (the finer: both axes have the same metres per pixel), so
    // the grid's cells are square.
    const double step = std::min(xt[1] - xt[0], yt[1] - yt[0]);
    xt = ticks_with_step(x0, x1, step), yt = ticks_with_step(y0, y1, step);
  }
  const double x_step = xt.size() > 1 ? xt[1] - xt[0] : 1, y_step = yt.size() > 1 ? yt[1] - yt[0] : 1;
  for (double t : xt) {
    line(px(t), top, px(t), height_ - bottom, light, 2);
    const std::string s = format_tick(t, x_step);
    text(static_cast<int>(px(t)) - text_width(s) / 2, height_ - bottom + 8, s, black);
  }
  for (double t : yt) {
    line(left, py(t), width_ - right, py(t), light, 2);
    const std::string s = format_tick(t, y_step);
    text(left - 8 - text_width(s), static_cast<int>(py(t)) - kTextHeight / 2, s, black);
  }
  line(left, height_ - bottom, width_ - right, height_ - bottom, grey, 2);
  line(left, top, left, height_ - bottom, grey, 2);
  // Coloured series first, single-colour ones over them and thinner: a reference path (ground
  // truth) stays visible where the path compared with it runs along it.
  for (const bool coloured : {true, false}) {
    for (const auto& s : series_) {
      if (s.value.empty() == coloured) continue;
      double lo = INFINITY, hi = -INFINITY;
      for (double v : s.value) lo = std::min(lo, v), hi = std::max(hi, v);
      const double span = hi > lo ? hi - lo : 1;
      for (std::size_t i = 1; i < s.x.size(); ++i) {
        const Color c =
            coloured ? scale_color((0.5 * (s.value[i - 1] + s.value[i]) - lo) / span) : s.color;
        line(px(s.x[i - 1]), py(s.y[i - 1]), px(s.x[i]), py(s.y[i]), c,
             coloured ? kColouredWidth : kLineWidth);
      }
    }
  }
  for (const auto& m : markers_) {
    const int x = static_cast<int>(px(m.x)), y = static_cast<int>(py(m.y));
    fill(img, x - 6, y - 6, x + 7, y + 7, black);
    fill(img, x - 4, y - 4, x + 5, y + 5, m.color);
    // Right, left, above or below the marker, wherever the label covers the fewest drawn pixels
    // (the path leaves a marker on one side), moved inside the image.
    const int w = text_width(m.label);
    const std::array<std::array<int, 2>, 4> candidates = {{{x + 10, y - kTextHeight / 2},
                                                           {x - 10 - w, y - kTextHeight / 2},
                                                           {x - w / 2, y - 10 - kTextHeight},
                                                           {x - w / 2, y + 10}}};
    std::array<int, 2> best = candidates[0];
    long fewest = -1;
    for (auto [cx, cy] : candidates) {
      cx = std::clamp(cx, kTextInset, std::max(kTextInset, width_ - kTextInset - w));
      cy = std::clamp(cy, kTextInset, std::max(kTextInset, height_ - kTextInset - kTextDepth));
      long covered = 0;
      for (int v = cy; v < std::min(height_, cy + kTextHeight); ++v)
        for (int u = cx; u < std::min(width_, cx + w); ++u)
          covered += img.at(u, v, 0) != 255 || img.at(u, v, 1) != 255 || img.at(u, v, 2) != 255;
      if (fewest < 0 || covered < fewest) fewest = covered, best = {cx, cy};
    }
    text(best[0], best[1], m.label, black);
  }
  if (!x_label_.empty())
    text(left + (plot_w - text_width(x_label_)) / 2, height_ - bottom + 32, x_label_, black);
  if (!y_label_.empty()) text(8, top - 20, y_label_, black);
  if (!title_.empty()) text(left, 4, title_, black);
  for (const auto& item : legend) {
    const Series& s = *item.series;
    if (s.value.empty()) {
      line(item.x, item.y + kTextHeight / 2, item.x + 20, item.y + kTextHeight / 2, s.color,
           kLineWidth + 1);
      text(item.x + 26, item.y, s.name, black);
      continue;
    }
    // A coloured series: its lowest value, the scale, its highest value, then its name.
    text(item.x, item.y, item.low, black);
    const int bar_x = item.x + text_width(item.low) + 6;
    for (int i = 0; i < kColourBar; ++i) {
      fill(img, bar_x + i, item.y, bar_x + i + 1, item.y + kTextHeight,
           scale_color(static_cast<double>(i) / (kColourBar - 1)));
    }
    text(bar_x + kColourBar + 6, item.y, item.high, black);
    text(bar_x + kColourBar + 6 + text_width(item.high) + 10, item.y, s.name, black);
  }
  return img;
}

}  // namespace app
