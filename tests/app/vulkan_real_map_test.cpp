// The Vulkan backend against the CPU reference on real trained 3DGS maps (../shared/data):
// forward images pixel by pixel and every gradient group (norm-wise, see parity.h), from
// orbit views around each map.
#include <gtest/gtest.h>

#include <random>
#include <string>

#include "io/ply_io.h"
#include "viewer/views.h"
#include "support/backends.h"
#include "support/parity.h"
#include "support/test_data.h"

namespace {

class VulkanRealMap : public ::testing::TestWithParam<const char*> {};

TEST_P(VulkanRealMap, ForwardAndBackwardMatchCpu) {
  GSLAM_REQUIRE_SHARED_DATA(path, GetParam());
  GSLAM_REQUIRE_BACKEND(cpu, "cpu");
  GSLAM_REQUIRE_BACKEND(gpu, "vulkan");
  const splat::Gaussians map = app::read_ply(path).gaussians;
  const auto views =
      app::orbit_cameras(app::map_extent(map), 3, 160, 120, Eigen::Vector3d::UnitY());
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> u(-1.f, 1.f);
  for (std::size_t v = 0; v < views.size(); ++v) {
    const std::string label = std::string(GetParam()) + " view " + std::to_string(v);
    const auto a = cpu.forward(map, views[v], {});
    const auto b = gpu.forward(map, views[v], {});
    ASSERT_GT(a.stats.visible, 1000u) << label;
    gslam::test::expect_forward_parity(a, b, false, label);
    splat::ImageGrads d;
    d.rgb.resize(a.rgb.size());
    d.depth.resize(a.depth.size());
    for (float& x : d.rgb) x = u(rng);
    for (float& x : d.depth) x = 0.1f * u(rng);
    d = gslam::test::zero_near_cutoffs(a, std::move(d));
    gslam::test::expect_backward_parity(cpu.backward(a, d), gpu.backward(b, d), label,
                                        gslam::test::GradientRule::kNormwise);
  }
}

INSTANTIATE_TEST_SUITE_P(
    Maps, VulkanRealMap,
    ::testing::Values("v3dg_donut_3dgs_ply/fused.ply",
                      "supersplat_fruit_drops_3dgs_ply/fruit_drops_minimal.ply"),
    [](const auto& info) {
      return std::string(info.param).substr(0, std::string(info.param).find('_'));
    });

}  // namespace
