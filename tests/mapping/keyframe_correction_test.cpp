// Loop-closure corrections in the mapper: each Gaussian moves rigidly with the keyframe that
// seeded it, and so do the stored keyframes, through pruning and checkpoints.
#include <gtest/gtest.h>

#include "datasets/dataset.h"
#include "datasets/synthetic_sequence.h"
#include "mapping/mapper.h"
#include "splat/error.h"
#include "splat/rasterizer.h"
#include "support/synthetic_dataset.h"
#include "support/temp_dir.h"

namespace {

TEST(KeyframeCorrection, GaussiansMoveRigidlyWithTheKeyframeThatSeededThem) {
  gslam::test::TempDir dir;
  app::SyntheticOptions o;
  o.frames = 12;
  const app::Dataset dataset = gslam::test::synthetic_dataset(dir / "seq", o);
  auto rasterizer = splat::make_cpu_rasterizer();
  mapping::MapperConfig config;
  config.iterations = 2;
  mapping::Mapper mapper(*rasterizer, config);
  for (std::size_t i : {0u, 11u}) mapper.add_keyframe(dataset.load(i), dataset.entries[i].T_world_cam_truth->inverse());
  const mapping::MapperState before = mapper.state();
  ASSERT_EQ(before.anchors.size(), before.map.size());
  std::size_t seeded_by_second = 0;
  for (uint32_t a : before.anchors) seeded_by_second += a == 1;
  ASSERT_GT(seeded_by_second, 0u);
  ASSERT_LT(seeded_by_second, before.map.size());
  // Keyframe 0 stays, keyframe 1 turns 3 degrees about y and moves 4 cm.
  Eigen::Isometry3d turn = Eigen::Isometry3d::Identity();
  turn.linear() = Eigen::AngleAxisd(3 * M_PI / 180, Eigen::Vector3d::UnitY()).toRotationMatrix();
  turn.translation() = Eigen::Vector3d(0.04, 0, -0.01);
  mapper.correct_keyframes({Eigen::Isometry3d::Identity(), turn});
  const mapping::MapperState after = mapper.state();
  for (std::size_t i = 0; i < before.map.size(); ++i) {
    const Eigen::Vector3d p(before.map.means[i * 3], before.map.means[i * 3 + 1], before.map.means[i * 3 + 2]);
    const Eigen::Vector3d q(after.map.means[i * 3], after.map.means[i * 3 + 1], after.map.means[i * 3 + 2]);
    const Eigen::Vector3d expected = before.anchors[i] == 1 ? turn * p : p;
    EXPECT_LT((q - expected).norm(), 1e-5) << "Gaussian " << i << " anchored to " << before.anchors[i];
  }
  // The stored keyframes' poses moved the same way (camera-to-world: left-multiplied).
  for (const auto& [number, T_cam_world] : mapper.keyframe_poses()) {
    const Eigen::Isometry3d expected = number == 1 ? turn * dataset.entries[11].T_world_cam_truth.value()
                                                   : dataset.entries[0].T_world_cam_truth.value();
    EXPECT_LT((T_cam_world.inverse().matrix() - expected.matrix()).cwiseAbs().maxCoeff(), 1e-9) << number;
  }
  EXPECT_THROW(mapper.correct_keyframes({turn}), splat::Error) << "one correction per keyframe added";
}

}  // namespace
