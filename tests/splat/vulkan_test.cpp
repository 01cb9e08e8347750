// The Vulkan backend against the CPU reference (runs on lavapipe in CI), and its device
// handling. Skipped without a device unless GSLAM_REQUIRE_GPU_TESTS makes that a failure.
#include <gtest/gtest.h>

#include <random>
#include <string>
#include <tuple>

#include "splat/error.h"
#include "splat/vulkan_rasterizer.h"
#include "support/backends.h"
#include "support/expect_error.h"
#include "support/parity.h"
#include "support/random_scene.h"

namespace {

using gslam::test::SceneOptions;

struct ParityCase {
  const char* name;
  SceneOptions scene;
};
void PrintTo(const ParityCase& c, std::ostream* os) { *os << c.name; }

SceneOptions scene(uint32_t seed, int count, int degree, int width, int height,
                   double max_opacity) {
  SceneOptions o;
  o.seed = seed;
  o.count = count;
  o.sh_degree = degree;
  o.width = width;
  o.height = height;
  o.max_opacity = max_opacity;
  return o;
}

// From a few smooth splats to thousands of nearly opaque ones (pixels that saturate and stop
// early), image sizes that are and are not multiples of the tile, every SH degree.
const ParityCase kCases[] = {
    {"Few", scene(1, 8, 3, 64, 48, 0.8)},
    {"Hundreds", scene(2, 300, 2, 100, 70, 0.99)},
    {"Thousands", scene(3, 3000, 1, 160, 120, 0.99)},
    {"RaggedTiles", scene(4, 2000, 0, 131, 77, 0.99)},
};

// (Vulkan variant, scene): both backward reductions are checked.
class VulkanParity : public ::testing::TestWithParam<std::tuple<const char*, ParityCase>> {
 protected:
  const char* variant() const { return std::get<0>(GetParam()); }
  const ParityCase& parity_case() const { return std::get<1>(GetParam()); }
};

// Fixed-seed upstream gradients for every output, none from pixels near a compositing cut-off
// (see parity.h).
splat::ImageGrads random_image_grads(const splat::ForwardResult& f, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  splat::ImageGrads d;
  d.rgb.resize(f.rgb.size());
  d.alpha.resize(f.alpha.size());
  d.depth.resize(f.depth.size());
  for (float& v : d.rgb) v = u(rng);
  for (float& v : d.alpha) v = u(rng);
  for (float& v : d.depth) v = 0.2f * u(rng);
  return gslam::test::zero_near_cutoffs(f, std::move(d));
}

TEST_P(VulkanParity, ForwardMatchesCpuStageByStage) {
  GSLAM_REQUIRE_BACKEND(cpu, "cpu");
  GSLAM_REQUIRE_BACKEND(gpu, variant());
  const auto s = gslam::test::make_random_scene<float>(parity_case().scene);
  splat::RenderSettings settings;
  settings.background = {0.1f, 0.4f, 0.7f};
  const auto a = cpu.forward(s.gaussians, s.camera, settings);
  const auto b = gpu.forward(s.gaussians, s.camera, settings);
  EXPECT_GT(a.stats.intersections, 0u);
  gslam::test::expect_forward_parity(a, b, true, parity_case().name);
}

TEST_P(VulkanParity, BackwardMatchesCpuForEveryParameterGroupAndThePose) {
  GSLAM_REQUIRE_BACKEND(cpu, "cpu");
  GSLAM_REQUIRE_BACKEND(gpu, variant());
  const auto s = gslam::test::make_random_scene<float>(parity_case().scene);
  const auto a = cpu.forward(s.gaussians, s.camera, {});
  const auto b = gpu.forward(s.gaussians, s.camera, {});
  const splat::ImageGrads d = random_image_grads(a, 7);
  gslam::test::expect_backward_parity(cpu.backward(a, d), gpu.backward(b, d), parity_case().name);
}

TEST_P(VulkanParity, PoseJacobianMatchesCpu) {
  GSLAM_REQUIRE_BACKEND(cpu, "cpu");
  GSLAM_REQUIRE_BACKEND(gpu, variant());
  const auto s = gslam::test::make_random_scene<float>(parity_case().scene);
  const auto a = cpu.forward(s.gaussians, s.camera, {});
  const auto b = gpu.forward(s.gaussians, s.camera, {});
  std::vector<float> cpu_jacobian, gpu_jacobian;
  cpu.pose_jacobian(a, cpu_jacobian);
  gpu.pose_jacobian(b, gpu_jacobian);
  gslam::test::expect_pose_jacobian_parity(a, cpu_jacobian, gpu_jacobian,
                                           std::string(parity_case().name) + " pose Jacobian");
}

INSTANTIATE_TEST_SUITE_P(Scenes, VulkanParity,
                         ::testing::Combine(::testing::Values("vulkan", "vulkan_portable"),
                                            ::testing::ValuesIn(kCases)),
                         [](const auto& info) {
                           return std::string(std::get<0>(info.param)) + "_" +
                                  std::get<1>(info.param).name;
                         });

TEST(VulkanBackend, RenderSettingsMatchCpu) {
  GSLAM_REQUIRE_BACKEND(cpu, "cpu");
  GSLAM_REQUIRE_BACKEND(gpu, "vulkan");
  const auto s = gslam::test::make_random_scene<float>(scene(5, 400, 3, 96, 64, 0.95));
  splat::RenderSettings settings;
  settings.sh_degree = 1;  // the map has degree 3: coefficients above 1 are ignored
  settings.sh_direction_gradient = false;
  settings.background = {1.f, 0.5f, 0.f};
  const auto a = cpu.forward(s.gaussians, s.camera, settings);
  const auto b = gpu.forward(s.gaussians, s.camera, settings);
  gslam::test::expect_forward_parity(a, b, true, "sh degree 1");
  const splat::ImageGrads d = random_image_grads(a, 3);
  gslam::test::expect_backward_parity(cpu.backward(a, d), gpu.backward(b, d), "sh degree 1");
}

// Backward on a forward result the Vulkan backend did not make (here the CPU's) renders its
// inputs again on the device rather than failing or using stale buffers.
TEST(VulkanBackend, BackwardAcceptsAForwardResultFromAnotherBackend) {
  GSLAM_REQUIRE_BACKEND(cpu, "cpu");
  GSLAM_REQUIRE_BACKEND(gpu, "vulkan");
  const auto s = gslam::test::make_random_scene<float>(scene(6, 200, 2, 80, 60, 0.9));
  const auto a = cpu.forward(s.gaussians, s.camera, {});
  const splat::ImageGrads d = random_image_grads(a, 11);
  gslam::test::expect_backward_parity(cpu.backward(a, d), gpu.backward(a, d), "cpu forward");
}

// Without intermediates the images are the same, the per-Gaussian buffers stay on the device,
// and backward still matches.
TEST(VulkanBackend, ImagesOnlyForwardSkipsIntermediatesAndBackwardStillMatches) {
  GSLAM_REQUIRE_BACKEND(cpu, "cpu");
  GSLAM_REQUIRE_BACKEND(gpu, "vulkan");
  const auto s = gslam::test::make_random_scene<float>(scene(10, 500, 2, 96, 64, 0.9));
  const auto a = cpu.forward(s.gaussians, s.camera, {});
  const auto b = gpu.forward(s.gaussians, s.camera, splat::images_only());
  EXPECT_TRUE(b.means2d.empty());
  EXPECT_TRUE(b.sorted_ids.empty());
  gslam::test::expect_forward_parity(a, b, false, "images only");
  const splat::ImageGrads d = random_image_grads(a, 13);
  gslam::test::expect_backward_parity(cpu.backward(a, d), gpu.backward(b, d), "images only");
}

// Buffers grow with the map and are reused across frames: small, large, small again.
TEST(VulkanBackend, BuffersGrowWithTheMapAndReportDeviceMemory) {
  GSLAM_REQUIRE_BACKEND(cpu, "cpu");
  GSLAM_REQUIRE_BACKEND(gpu, "vulkan");
  for (int count : {50, 20000, 50}) {
    const auto s = gslam::test::make_random_scene<float>(scene(8, count, 1, 128, 96, 0.9));
    const auto a = cpu.forward(s.gaussians, s.camera, {});
    const auto b = gpu.forward(s.gaussians, s.camera, {});
    gslam::test::expect_forward_parity(a, b, false, std::to_string(count) + " Gaussians");
    // Means, log-scales, rotations and SH alone take 13 floats per Gaussian on the device.
    EXPECT_GE(gpu.device_memory_bytes(), std::size_t(count) * 13 * 4) << count << " Gaussians";
  }
}

// The bus, as the backend counts it (what a device-resident mapping loop must cut): today every
// render uploads the whole map (nothing else grows with it) and every backward pass downloads
// every parameter's gradient and uploads only the image gradients. The CPU backend moves nothing.
TEST(VulkanBackend, TransfersCountTheMapUpAndItsGradientsDown) {
  GSLAM_REQUIRE_BACKEND(cpu, "cpu");
  GSLAM_REQUIRE_BACKEND(gpu, "vulkan");
  struct Moved {
    splat::Rasterizer::Transfers forward, backward;
  };
  const int width = 96, height = 64;
  const std::size_t pixels = std::size_t(width) * height;
  auto measure = [&](splat::Rasterizer& r, int count) {
    const auto s = gslam::test::make_random_scene<float>(scene(11, count, 1, width, height, 0.9));
    r.reset_transfers();
    const auto f = r.forward(s.gaussians, s.camera, splat::images_only());
    Moved m;
    m.forward = r.transfers();
    r.reset_transfers();
    splat::ImageGrads d;
    d.rgb.assign(f.rgb.size(), 1e-3f);
    d.alpha.assign(f.alpha.size(), 1e-3f);
    d.depth.assign(f.depth.size(), 1e-3f);
    r.backward(f, d);
    m.backward = r.transfers();
    return m;
  };
  const Moved cpu_moved = measure(cpu, 300);
  EXPECT_EQ(cpu_moved.forward.to_device + cpu_moved.forward.to_host + cpu_moved.backward.to_device + cpu_moved.backward.to_host, 0u);
  const int small = 300, large = 2300;
  const Moved a = measure(gpu, small), b = measure(gpu, large);
  const std::size_t per_gaussian = (3 + 3 + 4 + 1 + 4 * 3) * sizeof(float);  // SH degree 1
  const std::size_t added = std::size_t(large - small);
  EXPECT_EQ(b.forward.to_device - a.forward.to_device, added * per_gaussian);
  EXPECT_GE(a.forward.to_device, std::size_t(small) * per_gaussian);
  EXPECT_GE(a.forward.to_host, pixels * 6 * sizeof(float));  // RGB, alpha, depth, normalized depth
  EXPECT_EQ(a.backward.to_device, pixels * 5 * sizeof(float));  // d RGB, d alpha, d depth
  EXPECT_EQ(b.backward.to_device, a.backward.to_device);
  EXPECT_GE(b.backward.to_host - a.backward.to_host, added * per_gaussian);
}

// The portable reduction is deterministic bit for bit (float atomics add in varying order).
TEST(VulkanBackend, PortableReductionIsDeterministic) {
  GSLAM_REQUIRE_BACKEND(gpu, "vulkan_portable");
  const auto s = gslam::test::make_random_scene<float>(scene(9, 1500, 2, 96, 64, 0.99));
  const auto a = gpu.forward(s.gaussians, s.camera, {});
  const auto b = gpu.forward(s.gaussians, s.camera, {});
  EXPECT_EQ(a.rgb, b.rgb);
  EXPECT_EQ(a.sorted_ids, b.sorted_ids);
  const splat::ImageGrads d = random_image_grads(a, 5);
  const auto ga = gpu.backward(a, d), gb = gpu.backward(b, d);
  EXPECT_EQ(ga.d_gaussians.means, gb.d_gaussians.means);
  EXPECT_EQ(ga.d_loss_d_pose, gb.d_loss_d_pose);
}

TEST(VulkanBackend, EmptyMapGivesBackgroundAndZeroGradients) {
  GSLAM_REQUIRE_BACKEND(gpu, "vulkan");
  splat::Camera cam;
  cam.width = 40;
  cam.height = 30;
  cam.fx = cam.fy = 30;
  cam.cx = 20;
  cam.cy = 15;
  const splat::Gaussians empty;
  const auto f = gpu.forward(empty, cam, {});
  ASSERT_EQ(f.alpha.size(), 1200u);
  for (float a : f.alpha) ASSERT_EQ(a, 0.f);
  splat::ImageGrads d;
  d.rgb.assign(f.rgb.size(), 1.f);
  const auto g = gpu.backward(f, d);
  EXPECT_EQ(g.d_gaussians.size(), 0u);
  EXPECT_EQ(g.d_loss_d_pose, splat::PoseGradient::Zero());
}

TEST(VulkanDevice, ListsDevicesAndRejectsAnIndexOutOfRange) {
  if (!splat::vulkan_backend_built()) GTEST_SKIP() << "this build has no Vulkan backend";
  std::vector<splat::VulkanDeviceInfo> devices;
  try {
    devices = splat::list_vulkan_devices();
  } catch (const splat::Error& e) {
    if (gslam::test::gpu_tests_required()) FAIL() << e.what();
    GTEST_SKIP() << e.what();
  }
  ASSERT_FALSE(devices.empty());
  for (const auto& d : devices) {
    EXPECT_FALSE(d.name.empty());
    EXPECT_EQ(d.usable, d.problem.empty()) << d.name;
  }
  GSLAM_EXPECT_ERROR(splat::make_vulkan_rasterizer({99}), "--device 99 out of range");
}

}  // namespace
