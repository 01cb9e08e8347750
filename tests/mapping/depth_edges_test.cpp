// Depth edges: jumps between neighbours and the borders of holes, widened by a radius.
#include <gtest/gtest.h>

#include "mapping/depth_edges.h"
#include "splat/error.h"

namespace {

TEST(DepthEdges, MarksJumpsAndHoleBordersWithinTheRadius) {
  // 8x3: a near surface (1 m) left of a far one (2 m), a hole at the right end; one noisy
  // pixel (1.05 m) that is no edge at a 10% jump.
  std::vector<float> depth(8 * 3, 1.f);
  for (int y = 0; y < 3; ++y) {
    for (int x = 3; x < 7; ++x) depth[y * 8 + x] = 2.f;
    depth[y * 8 + 7] = 0.f;
  }
  depth[1 * 8 + 1] = 1.05f;
  const std::vector<uint8_t> edges = mapping::depth_edges(depth, 8, 3, 0.1, 0);
  for (int y = 0; y < 3; ++y) {
    const uint8_t expected[8] = {0, 0, 1, 1, 0, 0, 1, 1};  // both sides of the jump and of the hole's border
    for (int x = 0; x < 8; ++x) EXPECT_EQ(edges[y * 8 + x], expected[x]) << x << "," << y;
  }
  const std::vector<uint8_t> wide = mapping::depth_edges(depth, 8, 3, 0.1, 1);
  for (int y = 0; y < 3; ++y) {
    const uint8_t expected[8] = {0, 1, 1, 1, 1, 1, 1, 1};
    for (int x = 0; x < 8; ++x) EXPECT_EQ(wide[y * 8 + x], expected[x]) << x << "," << y;
  }
}

TEST(DepthEdges, RefusesBadSizesAndParameters) {
  EXPECT_THROW(mapping::depth_edges(std::vector<float>(5, 1.f), 2, 3, 0.1, 1), splat::Error);
  EXPECT_THROW(mapping::depth_edges(std::vector<float>(6, 1.f), 2, 3, 0, 1), splat::Error);
  EXPECT_THROW(mapping::depth_edges(std::vector<float>(6, 1.f), 2, 3, 0.1, -1), splat::Error);
}

}  // namespace
