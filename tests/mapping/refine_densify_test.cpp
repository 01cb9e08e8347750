// Densification in the final refinement: a frame's uncovered pixels get Gaussians, those without
// a depth measurement only when refine_seed_depth_holes asks for them, at depth filled in from
// their measured neighbours.
#include <algorithm>

#include <gtest/gtest.h>

#include "datasets/dataset.h"
#include "datasets/synthetic_sequence.h"
#include "mapping/mapper.h"
#include "splat/rasterizer.h"
#include "support/synthetic_dataset.h"
#include "support/temp_dir.h"

namespace {

TEST(RefineDensify, SeedsUncoveredHolesOnlyWhenAskedAndAtTheirNeighboursDepth) {
  gslam::test::TempDir dir;
  app::SyntheticOptions o;
  o.frames = 1;
  const app::Dataset dataset = gslam::test::synthetic_dataset(dir / "seq", o);
  // The left half of the frame has no depth: the keyframe seeds the right half alone.
  splat::RgbdFrame frame = dataset.load(0);
  const int w = frame.width(), h = frame.height();
  float nearest = 1e9f, farthest = 0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      float& z = frame.depth[static_cast<std::size_t>(y) * w + x];
      if (x < w / 2) {
        z = 0;
      } else if (z > 0) {
        nearest = std::min(nearest, z), farthest = std::max(farthest, z);
      }
    }
  }
  const Eigen::Isometry3d T_cam_world = dataset.entries[0].T_world_cam_truth->inverse();
  auto rasterizer = splat::make_cpu_rasterizer();
  auto left_half_covered = [&](const splat::Gaussians& map) {
    const splat::ForwardResult r = rasterizer->forward(map, splat::posed(frame.camera, T_cam_world), splat::images_only());
    std::size_t covered = 0;
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w / 2; ++x) covered += r.alpha[static_cast<std::size_t>(y) * w + x] > 0.5f ? 1 : 0;
    }
    return static_cast<double>(covered) / (static_cast<double>(w / 2) * h);
  };
  auto run = [&](bool densify, bool holes) {
    mapping::MapperConfig config;
    config.iterations = 0;
    config.refine_seed_depth_holes = holes;
    mapping::Mapper mapper(*rasterizer, config);
    mapper.add_keyframe(frame, T_cam_world);
    const std::size_t seeded = mapper.map().size();
    Eigen::Isometry3d pose = T_cam_world;
    mapper.refine(mapper.refinement_frame(frame), pose, nullptr, 0, densify);
    return std::make_pair(seeded, mapper.map());
  };
  const auto [seeded, plain] = run(true, false);
  EXPECT_EQ(plain.size(), seeded) << "no depth, no seeds: the uncovered half stays empty";
  EXPECT_LT(left_half_covered(plain), 0.1);
  const auto [seeded_again, filled] = run(true, true);
  EXPECT_EQ(run(false, true).second.size(), seeded) << "refine without densify adds nothing";
  ASSERT_GT(filled.size(), seeded_again);
  const double coverage = left_half_covered(filled);
  std::printf("hole seeding: %zu -> %zu Gaussians, left half %.0f%% covered\n", seeded_again, filled.size(), 100 * coverage);
  EXPECT_GT(coverage, 0.9);
  // New Gaussians sit at depths the frame measured next to the hole.
  for (std::size_t i = seeded_again; i < filled.size(); ++i) {
    const Eigen::Vector3d p = T_cam_world * Eigen::Vector3d(filled.means[i * 3], filled.means[i * 3 + 1], filled.means[i * 3 + 2]);
    ASSERT_GE(p.z(), nearest * 0.999) << "Gaussian " << i;
    ASSERT_LE(p.z(), farthest * 1.001) << "Gaussian " << i;
  }
}

}  // namespace
