#pragma once
#include <array>
#include <string>
#include <vector>

#include "splat/image.h"

namespace app {

// A line plot rendered into an RGB image: axes scaled to the data with a margin around it,
// ticks at round values with their numbers, axis titles, polylines in given colours or
// coloured by a value along them (with a colour bar), labelled markers and a legend in a band
// above the plot area (it never hides data). Every label lies whole inside the image. Enough
// for trajectories and error curves.
class LinePlot {
 public:
  LinePlot(int width, int height);
  // Adds a polyline (x[i], y[i]) in an RGB colour, 2 px wide; a non-empty name goes into the
  // legend. Single-colour polylines are drawn over coloured ones (add_coloured), so a reference
  // such as ground truth stays visible along the path compared with it.
  void add(const std::vector<double>& x, const std::vector<double>& y, std::array<uint8_t, 3> color,
           std::string name = {});
  // A polyline coloured by value[i] along it (blue at the lowest, red at the highest), 5 px wide,
  // with a colour bar naming `name` and the range.
  void add_coloured(const std::vector<double>& x, const std::vector<double>& y, const std::vector<double>& value,
                    std::string name);
  // A filled square marker at (x, y) with a label beside it (start and end of a trajectory):
  // right of it, or left where the image ends.
  void mark(double x, double y, std::array<uint8_t, 3> color, std::string label);
  // Keeps one unit the same length on both axes (for top views): the data's extent plus a
  // margin, centred in the plot area, the shorter range widened to fill it.
  void equal_axes(bool equal) { equal_ = equal; }
  void labels(std::string x_label, std::string y_label) {
    x_label_ = std::move(x_label);
    y_label_ = std::move(y_label);
  }
  void title(std::string text) { title_ = std::move(text); }
  splat::Image8 render() const;

 private:
  struct Series {
    std::vector<double> x, y;
    std::array<uint8_t, 3> color;
    std::string name;
    std::vector<double> value;  // add_coloured: a value per point
  };
  struct Marker {
    double x, y;
    std::array<uint8_t, 3> color;
    std::string label;
  };
  int width_, height_;
  bool equal_ = false;
  std::string x_label_, y_label_, title_;
  std::vector<Series> series_;
  std::vector<Marker> markers_;
};

// The colour of t in [0, 1] on the plots' scale: blue, cyan, green, yellow, red.
std::array<uint8_t, 3> scale_color(double t);

// Round tick values (1, 2 or 5 times a power of ten apart) covering [lo, hi], about `count`.
std::vector<double> nice_ticks(double lo, double hi, int count);

}  // namespace app
