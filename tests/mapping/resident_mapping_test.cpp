// The same Mapper on the Vulkan backend's resident map (lavapipe in CI) and on the CPU backend's
// host loop, the reference: keyframes, a densifying sweep and pruning give the same map (its
// renders of views it was not fitted to) and the same keyframe poses.
#include <gtest/gtest.h>

#include <cstdio>

#include "datasets/dataset.h"
#include "datasets/synthetic_sequence.h"
#include "mapping/mapper.h"
#include "splat/error.h"
#include "splat/losses.h"
#include "splat/rasterizer.h"
#include "support/backends.h"
#include "support/synthetic_dataset.h"
#include "support/temp_dir.h"

namespace {

TEST(ResidentMapping, GivesTheCpuBackendsMapAndPoses) {
  GSLAM_REQUIRE_BACKEND(vulkan, "vulkan");
  gslam::test::TempDir dir;
  app::SyntheticOptions o;
  o.frames = 25;
  const app::Dataset dataset = gslam::test::synthetic_dataset(dir / "seq", o);
  auto cpu = splat::make_cpu_rasterizer();
  mapping::MapperConfig config;
  config.iterations = 10;
  // Poses move with the map, so the comparison covers the pose gradient too.
  config.pose_learning_rate = 2e-4;
  config.pose_rotation_learning_rate = 5e-5;
  mapping::Mapper reference(*cpu, config), device(vulkan, config);
  ASSERT_FALSE(reference.device_resident());
  ASSERT_TRUE(device.device_resident());
  auto truth = [&](std::size_t i) { return dataset.entries[i].T_world_cam_truth->inverse(); };

  vulkan.reset_transfers();
  int iterations = 0, keyframes = 0;
  std::size_t added = 0, largest = 0;
  for (std::size_t i = 0; i < 25; i += 4) {
    const splat::RgbdFrame frame = dataset.load(i);
    const mapping::MappingStats a = reference.add_keyframe(frame, truth(i));
    const mapping::MappingStats b = device.add_keyframe(frame, truth(i));
    iterations += b.iterations;
    ++keyframes;
    added += b.added;
    largest = std::max(largest, device.size() + b.pruned);
    EXPECT_EQ(a.window, b.window) << "keyframe " << i;
  }
  const splat::Rasterizer::Transfers moved = vulkan.transfers();
  // What a keyframe moves: its image up (colour and depth, at the mapping resolution) and its
  // new Gaussians; densification's mask down (a bit a pixel: the coverage test runs on the
  // device); and bits per Gaussian for the free-space and pruning tests. Nothing grows with the
  // map but the bits, here allowed a byte per Gaussian each way.
  const std::size_t pixels = std::size_t(o.width / config.resolution_factor) * std::size_t(o.height / config.resolution_factor);
  const std::size_t gaussian_bytes = (3 + 3 + 4 + 1 + 3) * 4;
  EXPECT_LE(moved.to_device, keyframes * (pixels * 4 * 4 + largest + 1024) + added * gaussian_bytes);
  EXPECT_LE(moved.to_host, keyframes * ((pixels + 31) / 32 * 4 + largest + 1024) + std::size_t(iterations) * 256);
  // The final refinement's path: frames outside the keyframes, densified, with the vignetting
  // learnt (refine_vignetting_rate), then a second pass, then pruning. The device keeps the
  // sweep's frames: the second pass uploads none of them.
  splat::Rasterizer::Transfers second_pass;
  for (int pass = 0; pass < 2; ++pass) {
    const splat::Rasterizer::Transfers before = vulkan.transfers();
    for (std::size_t i : {2u, 10u, 18u}) {
      for (mapping::Mapper* m : {&reference, &device}) {
        Eigen::Isometry3d T_cam_world = truth(i);
        m->refine(m->refinement_frame(dataset.load(i)), T_cam_world, nullptr, 3, pass == 0, i);
      }
    }
    second_pass.to_device = vulkan.transfers().to_device - before.to_device;
  }
  device.release_sweep_frames();
  EXPECT_LT(second_pass.to_device, 3 * 3 * 1024u) << "a few parameters a step, no frame (" << pixels * 16 << " bytes each)";
  reference.prune();
  device.prune();

  const std::size_t map_bytes = device.size() * (3 + 3 + 4 + 1 + 3) * 4;
  std::printf("resident mapping: %d steps over 7 keyframes moved %.1f KiB up, %.1f KiB down; the sweep's second pass "
              "%.1f KiB up; final map %zu vs %zu Gaussians (%.1f KiB on the device)\n",
              iterations, double(moved.to_device) / 1024, double(moved.to_host) / 1024,
              double(second_pass.to_device) / 1024, device.size(), reference.size(), double(map_bytes) / 1024);
  EXPECT_NEAR(double(device.size()), double(reference.size()), 0.03 * double(reference.size()));

  const auto poses = reference.keyframe_poses(), device_poses = device.keyframe_poses();
  ASSERT_EQ(poses.size(), device_poses.size());
  double moved_most = 0;
  for (std::size_t k = 0; k < poses.size(); ++k) {
    const Eigen::Isometry3d& a = poses[k].second;
    const Eigen::Isometry3d& b = device_poses[k].second;
    moved_most = std::max(moved_most, (a.inverse().translation() - truth(4 * poses[k].first).inverse().translation()).norm());
    EXPECT_LT((a.inverse().translation() - b.inverse().translation()).norm(), 1e-3) << "keyframe " << poses[k].first;
    EXPECT_LT(Eigen::AngleAxisd((a.linear() * b.linear().transpose()).eval()).angle(), 1e-3) << "keyframe " << poses[k].first;
  }
  EXPECT_GT(moved_most, 1e-4) << "the poses moved, so their agreement says something";
  EXPECT_NEAR(device.vignetting().k1, reference.vignetting().k1, 0.1 * std::abs(reference.vignetting().k1) + 1e-4);

  // Views the map was not fitted to, rendered by the same backend from both maps.
  for (std::size_t i : {1u, 13u, 23u}) {
    const splat::RgbdFrame frame = splat::downsample(dataset.load(i), 2);
    const splat::Camera camera = splat::posed(frame.camera, truth(i));
    const double a = splat::psnr(cpu->forward(reference.map(), camera, splat::images_only()).rgb, frame.rgb, 3);
    const double b = splat::psnr(cpu->forward(device.map(), camera, splat::images_only()).rgb, frame.rgb, 3);
    std::printf("frame %zu: %.3f dB from the CPU backend's map, %.3f dB from the resident map\n", i, a, b);
    EXPECT_NEAR(b, a, 0.1) << "frame " << i;
  }
}

}  // namespace

namespace {

// A checkpoint of a resident mapper (its map and Adam state read back from the device) restored
// into a fresh one, and a loop correction (the map read, moved on the host and written back):
// both mappers then continue alike.
TEST(ResidentMapping, CheckpointsAndLoopCorrectionsCarryTheDeviceState) {
  GSLAM_REQUIRE_BACKEND(vulkan, "vulkan");
  gslam::test::TempDir dir;
  app::SyntheticOptions o;
  o.frames = 13;
  o.width = 160, o.height = 120, o.focal = 130;  // small: the state's round trips are the point
  const app::Dataset dataset = gslam::test::synthetic_dataset(dir / "seq", o);
  mapping::MapperConfig config;
  config.iterations = 6;
  config.max_keyframes = 2;  // keyframe 0's image is dropped from the device, and must not be asked for
  auto truth = [&](std::size_t i) { return dataset.entries[i].T_world_cam_truth->inverse(); };
  mapping::Mapper original(vulkan, config);
  for (std::size_t i : {0u, 4u, 8u}) original.add_keyframe(dataset.load(i), truth(i));
  auto load = [&](std::size_t number) { return dataset.load(4 * number); };
  mapping::MapperState wrong = original.state();
  wrong.adam.v.sh_degree = 1;
  mapping::Mapper refusing(vulkan, config);
  EXPECT_THROW(refusing.restore(std::move(wrong), load), splat::Error) << "moments of another SH degree";
  mapping::Mapper restored(vulkan, config);
  restored.restore(original.state(), load);
  ASSERT_TRUE(restored.device_resident());
  EXPECT_EQ(restored.map().means, original.map().means);
  EXPECT_EQ(restored.state().adam.steps, original.state().adam.steps) << "the optimizer state came back from the device";

  Eigen::Isometry3d turn = Eigen::Isometry3d::Identity();
  turn.linear() = Eigen::AngleAxisd(0.02, Eigen::Vector3d::UnitY()).toRotationMatrix();
  turn.translation() = Eigen::Vector3d(0.01, 0, 0);
  const std::vector<Eigen::Isometry3d> correction = {Eigen::Isometry3d::Identity(), turn, turn};
  for (mapping::Mapper* m : {&original, &restored}) {
    m->correct_keyframes(correction);
    m->add_keyframe(dataset.load(12), truth(12));
  }
  const splat::Gaussians& a = original.map();
  const splat::Gaussians& b = restored.map();
  ASSERT_EQ(a.size(), b.size());
  float worst = 0;
  for (std::size_t k = 0; k < a.means.size(); ++k) worst = std::max(worst, std::abs(a.means[k] - b.means[k]));
  EXPECT_LT(worst, 1e-4f) << "metres; the float atomics' order may differ between runs";
}

}  // namespace
