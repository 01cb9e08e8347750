// Plots: round tick values, and that labels and series land where the axes say.
#include "io/plot.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace {

TEST(NiceTicks, StepsAreOneTwoOrFiveTimesAPowerOfTenAndCoverTheRange) {
  auto expect_ticks = [](const std::vector<double>& got, const std::vector<double>& want) {
    ASSERT_EQ(got.size(), want.size());
    for (std::size_t i = 0; i < got.size(); ++i) EXPECT_NEAR(got[i], want[i], 1e-12) << i;
  };
  expect_ticks(app::nice_ticks(0, 10, 5), {0, 2, 4, 6, 8, 10});
  expect_ticks(app::nice_ticks(0.13, 0.61, 5), {0.2, 0.3, 0.4, 0.5, 0.6});  // step 0.096 -> 0.1
  expect_ticks(app::nice_ticks(-2.2, 1.3, 6), {-2, -1, 0, 1});                // step 0.58 -> 1
  expect_ticks(app::nice_ticks(-2.2, 1.3, 10), {-2, -1.5, -1, -0.5, 0, 0.5, 1});  // 0.35 -> 0.5
  EXPECT_EQ(app::nice_ticks(1, 1, 5), std::vector<double>{1});  // empty range: one tick
}

// Counts pixels of exactly this colour in a rectangle.
int count(const splat::Image8& img, int x0, int y0, int x1, int y1, std::array<uint8_t, 3> c) {
  int n = 0;
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) n += img.at(x, y, 0) == c[0] && img.at(x, y, 1) == c[1] && img.at(x, y, 2) == c[2];
  return n;
}

TEST(LinePlot, DrawsTheSeriesInsideTheAxesAndTextInTheMargins) {
  app::LinePlot plot(400, 300);
  plot.labels("time (s)", "ATE (cm)");
  plot.title("a title");
  plot.add({0, 1, 2, 3}, {1, 3, 2, 4}, {200, 0, 0}, "estimate");
  const splat::Image8 img = plot.render();
  ASSERT_EQ(img.width, 400);
  ASSERT_EQ(img.height, 300);
  // The series lies right of the left margin (80 px) and above the bottom one (56 px).
  EXPECT_GT(count(img, 80, 0, 400, 244, {200, 0, 0}), 100);
  EXPECT_EQ(count(img, 0, 0, 78, 300, {200, 0, 0}), 0);
  // Tick numbers in the left margin, the x title in the bottom one, the title on top.
  EXPECT_GT(count(img, 0, 44, 78, 244, {0, 0, 0}), 50);
  EXPECT_GT(count(img, 80, 270, 400, 300, {0, 0, 0}), 50);
  EXPECT_GT(count(img, 80, 0, 300, 20, {0, 0, 0}), 20);
}

}  // namespace

namespace {

// Data never touches the frame of the axes; a coloured series runs from the scale's blue to its
// red; markers land on their points.
TEST(LinePlot, KeepsAMarginAndColoursBySeriesValueAndMarksPoints) {
  app::LinePlot plot(400, 300);
  plot.add_coloured({0, 1, 2, 3}, {0, 1, 2, 3}, {0, 1, 2, 3}, "error");
  plot.mark(0, 0, {10, 200, 10}, "start");
  const splat::Image8 img = plot.render();
  const std::array<uint8_t, 3> blue = app::scale_color(0), red = app::scale_color(1);
  EXPECT_EQ(blue, (std::array<uint8_t, 3>{40, 60, 220}));
  EXPECT_EQ(red, (std::array<uint8_t, 3>{220, 30, 30}));
  // The plot area is x in [80, 380), y in [48, 244) (a legend row above it); 4% margins keep
  // the line off its edges.
  EXPECT_EQ(count(img, 80, 48, 86, 244, app::scale_color(1.0 / 6)), 0);
  int plotted = 0;
  for (int k = 0; k <= 20; ++k) plotted += count(img, 90, 54, 372, 238, app::scale_color(k / 20.0));
  EXPECT_GT(plotted, 150) << "the series, in the scale's colours";
  EXPECT_EQ(count(img, 370, 48, 380, 52, red), 0) << "no data in the top-right corner margin";
  // The start marker: its colour where (0, 0) lands, 4% in from the bottom-left corner.
  const int x = 80 + static_cast<int>(0.04 / 1.08 * 300),
            y = 244 - static_cast<int>(0.04 / 1.08 * 196);
  EXPECT_GT(count(img, x - 5, y - 5, x + 6, y + 6, {10, 200, 10}), 40);
}

}  // namespace

namespace {

constexpr std::array<uint8_t, 3> kTruth = {150, 150, 150}, kEnd = {200, 0, 200};

// The bounding box of pixels of exactly this colour: {x0, y0, x1, y1}, x1 and y1 exclusive.
std::array<int, 4> box(const splat::Image8& img, std::array<uint8_t, 3> c) {
  std::array<int, 4> b = {img.width, img.height, 0, 0};
  for (int y = 0; y < img.height; ++y)
    for (int x = 0; x < img.width; ++x)
      if (img.at(x, y, 0) == c[0] && img.at(x, y, 1) == c[1] && img.at(x, y, 2) == c[2]) {
        b = {std::min(b[0], x), std::min(b[1], y), std::max(b[2], x + 1), std::max(b[3], y + 1)};
      }
  return b;
}

// A top view with the eval's layers: truth, estimate coloured by error, start and end marked.
app::LinePlot top_view(const std::vector<double>& x, const std::vector<double>& y) {
  app::LinePlot plot(640, 640);
  plot.equal_axes(true);
  plot.labels("x (m)", "z (m)");
  plot.title("top view, estimate aligned to ground truth");
  plot.add(x, y, kTruth, "ground truth");
  std::vector<double> error(x.size());
  for (std::size_t i = 0; i < error.size(); ++i) error[i] = static_cast<double>(i);
  plot.add_coloured(x, y, error, "estimate, error (cm)");
  plot.mark(x.front(), y.front(), {40, 180, 60}, "start");
  plot.mark(x.back(), y.back(), kEnd, "end");
  return plot;
}

// Equal axes: a 1 m x 0.1 m path (and a 0.1 m x 1 m one) keeps its aspect, centred in the plot
// area (x in [80, 620), y in [top, 584)).
TEST(LinePlot, EqualAxesKeepThePathsAspectAndCentreIt) {
  for (const bool wide : {true, false}) {
    const std::vector<double> a = {0, 1, 1, 0, 0}, b = {0, 0, 0.1, 0.1, 0};
    app::LinePlot plot(640, 640);
    plot.equal_axes(true);
    plot.add(wide ? a : b, wide ? b : a, kTruth);
    const auto [x0, y0, x1, y1] = box(plot.render(), kTruth);
    // The 2 px line adds 2 px to each side's length (its centre line spans the path).
    const double w = x1 - x0 - 2, h = y1 - y0 - 2;
    EXPECT_NEAR(wide ? w / h : h / w, 10.0, 0.2)
        << (wide ? "wide" : "tall") << ": " << w << " x " << h << " px";
    EXPECT_GT(std::max(w, h), 480) << "the path fills the plot area, less the margins";
    EXPECT_NEAR(0.5 * (x0 + x1), 350, 2) << "centred across";
    EXPECT_NEAR(0.5 * (y0 + y1), 0.5 * (24 + 584), 2) << "centred down";
  }
}

// Every label lies whole inside the image: nothing drawn on the outermost pixels, even for an
// end marker at the right edge of the data.
TEST(LinePlot, LabelsStayInsideTheImage) {
  const splat::Image8 img = top_view({0, 0.5, 1.0}, {0, 0.02, 0}).render();
  for (int x = 0; x < img.width; ++x)
    for (const int y : {0, 1, img.height - 2, img.height - 1})
      EXPECT_EQ(img.at(x, y, 0), 255) << "pixel " << x << ", " << y;
  for (int y = 0; y < img.height; ++y)
    for (const int x : {0, 1, img.width - 2, img.width - 1})
      EXPECT_EQ(img.at(x, y, 0), 255) << "pixel " << x << ", " << y;
  // The "end" label: black text near the end marker (x = 1 lands at about 600), beside its
  // black outline.
  const auto [x0, y0, x1, y1] = box(img, kEnd);
  ASSERT_LT(x0, x1) << "the end marker is drawn";
  const int near = count(img, x0 - 60, y0 - 40, std::min(img.width, x1 + 60), y1 + 40, {0, 0, 0});
  EXPECT_GT(near - count(img, x0 - 2, y0 - 2, x1 + 2, y1 + 2, {0, 0, 0}), 20)
      << "the label is drawn";
}

// The ground truth is drawn over the estimate: where both paths coincide it stays visible.
TEST(LinePlot, GroundTruthStaysVisibleWhereThePathsOverlap) {
  std::vector<double> x, y;
  for (int i = 0; i <= 50; ++i) x.push_back(0.02 * i), y.push_back(0.3 * std::sin(0.1 * i));
  const splat::Image8 img = top_view(x, y).render();
  EXPECT_GT(count(img, 80, 80, 620, 584, kTruth), 500) << "truth pixels along the whole path";
  int estimate = 0;  // saturated pixels: the error scale's colours (and the two markers)
  for (int y = 80; y < 584; ++y)
    for (int x = 80; x < 620; ++x) {
      const auto [lo, hi] = std::minmax({img.at(x, y, 0), img.at(x, y, 1), img.at(x, y, 2)});
      estimate += hi - lo > 60;
    }
  EXPECT_GT(estimate, 1000) << "the wider estimate shows on both sides of the truth";
}

}  // namespace
