// Plots: round tick values, and that labels and series land where the axes say.
#include <gtest/gtest.h>

#include "io/plot.h"

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
  // The plot area is x in [80, 380), y in [24, 244); 4% margins keep the line off its edges.
  EXPECT_EQ(count(img, 80, 24, 88, 244, app::scale_color(1.0 / 6)), 0);
  int plotted = 0;
  for (int k = 0; k <= 20; ++k) plotted += count(img, 90, 30, 372, 238, app::scale_color(k / 20.0));
  EXPECT_GT(plotted, 150) << "the series, in the scale's colours";
  EXPECT_EQ(count(img, 370, 24, 380, 30, red), 0) << "no data in the top-right corner margin";
  // The start marker: its colour where (0, 0) lands, 4% in from the bottom-left corner.
  const int x = 80 + static_cast<int>(0.04 / 1.08 * 300), y = 244 - static_cast<int>(0.04 / 1.08 * 220);
  EXPECT_GT(count(img, x - 5, y - 5, x + 6, y + 6, {10, 200, 10}), 40);
}

}  // namespace
