// Label fusion (mapping/label_fusion.h): votes by contribution, read from the backward pass,
// checked against the blending weights computed here, and labels rendered back.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "mapping/label_fusion.h"
#include "splat/error.h"
#include "splat/rasterizer.h"

namespace {

constexpr int kWidth = 48, kHeight = 32;

splat::Camera camera() {
  splat::Camera c;
  c.width = kWidth, c.height = kHeight;
  c.fx = c.fy = 40, c.cx = kWidth / 2.0, c.cy = kHeight / 2.0;
  return c;  // at the origin, looking down +z
}

// A wall of small opaque Gaussians 2 m in front of the camera, filling the view: columns left of
// the middle are class 1's, the others class 2's (in the label images below).
splat::Gaussians wall() {
  splat::Gaussians g;
  for (int y = -12; y <= 12; ++y) {
    for (int x = -20; x <= 20; ++x) {
      g.means.insert(g.means.end(), {static_cast<float>(x) * 0.1f, static_cast<float>(y) * 0.1f, 2.f});
      g.log_scales.insert(g.log_scales.end(), {std::log(0.06f), std::log(0.06f), std::log(0.01f)});
      g.rotations.insert(g.rotations.end(), {1.f, 0.f, 0.f, 0.f});
      g.opacity_logits.push_back(4.f);
      g.sh.insert(g.sh.end(), {0.3f, -0.2f, 0.1f});
    }
  }
  return g;
}

std::vector<uint16_t> halves(double noise = 0, uint32_t seed = 1) {
  std::vector<uint16_t> labels(kWidth * kHeight);
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> coin(0, 1);
  for (int y = 0; y < kHeight; ++y) {
    for (int x = 0; x < kWidth; ++x) {
      uint16_t id = x < kWidth / 2 ? 1 : 2;
      if (coin(rng) < noise) id = static_cast<uint16_t>(1 + (coin(rng) < 0.5));
      labels[y * kWidth + x] = id;
    }
  }
  return labels;
}

TEST(LabelFusion, EachGaussianTakesTheClassOfThePixelsItIsDrawnInto) {
  auto rasterizer = splat::make_cpu_rasterizer();
  const splat::Gaussians map = wall();
  mapping::LabelFusion fusion(map.size());
  fusion.add_view(*rasterizer, map, camera(), halves());
  const splat::GaussianLabels labels = fusion.result(2);
  ASSERT_EQ(labels.size(), map.size());
  std::size_t checked = 0;
  for (std::size_t i = 0; i < map.size(); ++i) {
    const float x = map.means[i * 3], y = map.means[i * 3 + 1];
    // Visible, and away from the boundary between the halves (x = 0).
    if (std::abs(x) < 0.15f || std::abs(x) > 1.0f || std::abs(y) > 0.6f) continue;
    ++checked;
    EXPECT_EQ(labels.best(i), x < 0 ? 1 : 2) << "Gaussian at " << x << ", " << y;
    EXPECT_GT(labels.probabilities[i * 2], 0.99f);
  }
  EXPECT_GT(checked, 100u);
  // Outside the view: no vote.
  for (std::size_t i = 0; i < map.size(); ++i) {
    if (std::abs(map.means[i * 3]) > 1.6f) {
      EXPECT_EQ(labels.best(i), 0) << i;
    }
  }
}

// The votes are the blending weights: a Gaussian straddling the boundary splits its votes as its
// footprint does, equally for one centred on it.
TEST(LabelFusion, VotesAreTheBlendingWeights) {
  auto rasterizer = splat::make_cpu_rasterizer();
  splat::Gaussians one;
  one.means = {0.f, 0.f, 2.f};
  one.log_scales = {std::log(0.1f), std::log(0.1f), std::log(0.1f)};
  one.rotations = {1.f, 0.f, 0.f, 0.f};
  one.opacity_logits = {0.f};
  one.sh = {0.f, 0.f, 0.f};
  mapping::LabelFusion fusion(1);
  fusion.add_view(*rasterizer, one, camera(), halves());
  const splat::GaussianLabels labels = fusion.result(2);
  EXPECT_NEAR(labels.probabilities[0], 0.5f, 0.03f);
  EXPECT_NEAR(labels.probabilities[1], 0.5f, 0.03f);
}

TEST(LabelFusion, VotingOverViewsAbsorbsNoisyLabels) {
  auto rasterizer = splat::make_cpu_rasterizer();
  const splat::Gaussians map = wall();
  mapping::LabelFusion fusion(map.size());
  for (uint32_t view = 0; view < 5; ++view) fusion.add_view(*rasterizer, map, camera(), halves(0.3, view + 1));
  const splat::GaussianLabels labels = fusion.result();
  const std::vector<uint16_t> rendered = mapping::render_labels(*rasterizer, map, labels, camera());
  const std::vector<uint16_t> truth = halves();
  std::size_t right = 0;
  for (std::size_t p = 0; p < truth.size(); ++p) right += rendered[p] == truth[p];
  // Off only along the boundary column pair, where a Gaussian covers both halves.
  EXPECT_GE(right, truth.size() - 2 * kHeight);
}

TEST(LabelFusion, RefusesLabelsOfAnotherSize) {
  auto rasterizer = splat::make_cpu_rasterizer();
  const splat::Gaussians map = wall();
  mapping::LabelFusion fusion(map.size());
  EXPECT_THROW(fusion.add_view(*rasterizer, map, camera(), std::vector<uint16_t>(10, 1)), splat::Error);
  mapping::LabelFusion wrong(3);
  EXPECT_THROW(wrong.add_view(*rasterizer, map, camera(), halves()), splat::Error);
}

}  // namespace
