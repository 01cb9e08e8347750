// Filling depth holes for seeding: measured pixels stay, each hole takes the farthest of its
// nearest measurements along the row and the column.
#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "mapping/depth_holes.h"
#include "splat/error.h"

namespace {

TEST(DepthHoles, MeasuredPixelsStayAndHolesTakeTheFartherNeighbour) {
  // 5x3; the middle row has a hole between a near (1 m) and a far (3 m) surface, as a depth
  // camera's shadow at a depth edge leaves it.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<float> depth = {
      1, 1, 2, 3, 3,
      1, 0, nan, 0, 3,
      1, 1, 2, 3, 3,
  };
  const std::vector<float> filled = mapping::fill_depth_holes(depth, 5, 3);
  ASSERT_EQ(filled.size(), depth.size());
  for (std::size_t p = 0; p < depth.size(); ++p) {
    if (depth[p] > 0) {
      EXPECT_EQ(filled[p], depth[p]) << "pixel " << p;
    }
  }
  // Row neighbours 1 and 3, column neighbours (above and below) 1, 2 and 3.
  EXPECT_EQ(filled[6], 3.f);
  EXPECT_EQ(filled[7], 3.f);
  EXPECT_EQ(filled[8], 3.f);
}

TEST(DepthHoles, ReachesAcrossWideHolesAndLeavesAnEmptyMapEmpty) {
  // A top band beyond the camera's range: filled from the nearest row measured below it.
  std::vector<float> depth(4 * 4, 0.f);
  for (int x = 0; x < 4; ++x) depth[3 * 4 + x] = 2.f + static_cast<float>(x);
  const std::vector<float> filled = mapping::fill_depth_holes(depth, 4, 4);
  for (int y = 0; y < 3; ++y) {
    for (int x = 0; x < 4; ++x) EXPECT_EQ(filled[y * 4 + x], 2.f + static_cast<float>(x)) << x << "," << y;
  }
  const std::vector<float> none = mapping::fill_depth_holes(std::vector<float>(6, 0.f), 3, 2);
  for (float z : none) EXPECT_EQ(z, 0.f);
}

TEST(DepthHoles, ASizeThatDoesNotMatchIsAnError) {
  EXPECT_THROW(mapping::fill_depth_holes(std::vector<float>(5, 1.f), 2, 3), splat::Error);
}

}  // namespace
