// The vectorized CPU compositing and the Vulkan shaders against the readable scalar oracle
// (splat::scalar_composite / scalar_reference_backward), each on its own projection's output,
// so the comparison isolates compositing. All three share one per-pixel formula (sigma, exp,
// alpha, with no fused multiply-adds), so alpha agrees bit for bit; a change of the formula on
// one side alone fails here.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "splat/cpu_reference.h"
#include "splat/error.h"
#include "support/backends.h"
#include "support/parity.h"
#include "support/random_scene.h"

namespace {

using gslam::test::SceneOptions;

// Dense scenes that exercise every cut-off: opacities from below kAlphaMin to above the
// kAlphaMax cap, and enough layers for transmittance to reach kTransmittanceMin.
SceneOptions dense_scene(uint32_t seed) {
  SceneOptions o;
  o.seed = seed;
  o.count = 400;
  o.sh_degree = 1;
  o.width = 96;
  o.height = 72;
  o.min_opacity = 0.002;
  o.max_opacity = 0.9999;
  o.min_scale = 0.02;
  o.max_scale = 0.3;
  return o;
}

// Alpha, transmittance and last contributors bit for bit; colour and depth bit for bit where
// both sides fuse their sums alike (the CPU passes), else within `sum_tolerance` (the shader
// adds them unfused).
template <typename T>
void expect_same_images(const splat::ForwardResultT<T>& ours, const splat::ForwardResultT<T>& oracle,
                        const std::string& label, T sum_tolerance = 0) {
  ASSERT_EQ(ours.alpha.size(), oracle.alpha.size()) << label;
  std::size_t alpha_diff = 0, trans_diff = 0, rgb_diff = 0, depth_diff = 0, last_diff = 0;
  for (std::size_t p = 0; p < oracle.alpha.size(); ++p) {
    alpha_diff += ours.alpha[p] != oracle.alpha[p];
    trans_diff += ours.final_transmittance[p] != oracle.final_transmittance[p];
    depth_diff += !(std::abs(ours.depth[p] - oracle.depth[p]) <= sum_tolerance);
    last_diff += ours.last_contributor[p] != oracle.last_contributor[p];
    for (int c = 0; c < 3; ++c) rgb_diff += !(std::abs(ours.rgb[p * 3 + c] - oracle.rgb[p * 3 + c]) <= sum_tolerance);
    if (ours.alpha[p] != oracle.alpha[p] && alpha_diff <= 5) {
      ADD_FAILURE() << label << ": pixel " << p << " alpha " << ours.alpha[p] << " against the oracle's "
                    << oracle.alpha[p] << " (last contributor " << ours.last_contributor[p] << " / "
                    << oracle.last_contributor[p] << ")";
    }
  }
  EXPECT_EQ(alpha_diff, 0u) << label << ": pixels whose alpha differs in any bit";
  EXPECT_EQ(trans_diff, 0u) << label << ": pixels whose final transmittance differs in any bit";
  EXPECT_EQ(last_diff, 0u) << label << ": pixels whose last contributor differs";
  EXPECT_EQ(rgb_diff, 0u) << label << ": colour values further apart than " << sum_tolerance;
  EXPECT_EQ(depth_diff, 0u) << label << ": depth values further apart than " << sum_tolerance;
}

// Upstream gradients of every output, uniform in [-1, 1], from a fixed seed.
template <typename T>
splat::ImageGradsT<T> random_image_grads(const splat::ForwardResultT<T>& f, uint32_t seed) {
  splat::ImageGradsT<T> d;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<T> u(-1, 1);
  d.rgb.resize(f.rgb.size());
  d.alpha.resize(f.alpha.size());
  d.depth.resize(f.depth.size());
  for (auto* v : {&d.rgb, &d.alpha, &d.depth}) {
    for (T& x : *v) x = u(rng);
  }
  return d;
}

// Counts the pixels where some splat's alpha is within a relative 1e-3 of kAlphaMin or of the
// kAlphaMax cap: the scenes must reach the cut-offs for the bit-exact checks to mean much.
std::size_t pixels_near_cutoffs(const splat::ForwardResult& f) {
  return gslam::test::near_cutoffs(f).pixels;
}

TEST(CompositeOracle, VectorizedCpuForwardMatchesTheScalarOracleBitForBit) {
  splat::ThreadPool pool(2);
  std::size_t near = 0;
  for (uint32_t seed = 1; seed <= 6; ++seed) {
    const auto scene = gslam::test::make_random_scene<float>(dense_scene(seed));
    const splat::ForwardResult fast = splat::reference_forward<float>(scene.gaussians, scene.camera, {}, pool);
    splat::ForwardResult oracle = fast;
    splat::scalar_composite(oracle);
    expect_same_images(fast, oracle, "float, seed " + std::to_string(seed));
    near += pixels_near_cutoffs(fast);
  }
  EXPECT_GT(near, 0u) << "no pixel near a cut-off: the scenes do not test them";
}

TEST(CompositeOracle, VectorizedDoubleForwardMatchesTheScalarOracleBitForBit) {
  splat::ThreadPool pool(2);
  const auto scene = gslam::test::make_random_scene<double>(dense_scene(7));
  const auto fast = splat::reference_forward<double>(scene.gaussians, scene.camera, {}, pool);
  auto oracle = fast;
  splat::scalar_composite(oracle);
  expect_same_images(fast, oracle, "double");
}

// Gradients sum per Gaussian in another order (per tile and row there, per pixel here): equal
// to rounding. Double: every element within 1e-9 of its group's scale; float: the parity rule.
TEST(CompositeOracle, VectorizedCpuBackwardMatchesTheScalarOracle) {
  splat::ThreadPool pool(2);
  for (uint32_t seed = 1; seed <= 3; ++seed) {
    const auto scene = gslam::test::make_random_scene<double>(dense_scene(seed));
    const auto f = splat::reference_forward<double>(scene.gaussians, scene.camera, {}, pool);
    const splat::ImageGradsT<double> d = random_image_grads(f, seed);
    const auto fast = splat::reference_backward<double>(f, d, pool);
    const auto oracle = splat::scalar_reference_backward<double>(f, d, pool);
    auto check = [&](const std::vector<double>& a, const std::vector<double>& b, const char* name) {
      ASSERT_EQ(a.size(), b.size()) << name;
      double scale = 0;
      for (double x : b) scale = std::max(scale, std::abs(x));
      ASSERT_GT(scale, 0) << name << ": no gradient at all";
      for (std::size_t i = 0; i < a.size(); ++i) {
        EXPECT_NEAR(a[i], b[i], 1e-9 * scale) << name << "[" << i << "], seed " << seed;
      }
    };
    check(fast.d_gaussians.means, oracle.d_gaussians.means, "means");
    check(fast.d_gaussians.log_scales, oracle.d_gaussians.log_scales, "log_scales");
    check(fast.d_gaussians.rotations, oracle.d_gaussians.rotations, "rotations");
    check(fast.d_gaussians.opacity_logits, oracle.d_gaussians.opacity_logits, "opacity_logits");
    check(fast.d_gaussians.sh, oracle.d_gaussians.sh, "sh");
    for (int k = 0; k < 6; ++k) {
      EXPECT_NEAR(fast.d_loss_d_pose[k], oracle.d_loss_d_pose[k], 1e-9 * oracle.d_loss_d_pose.norm()) << "pose " << k;
    }
  }
}

TEST(CompositeOracle, RefusesAResultWithoutIntermediates) {
  splat::ThreadPool pool(1);
  const auto scene = gslam::test::make_random_scene<float>(dense_scene(1));
  splat::ForwardResult f = splat::reference_forward<float>(scene.gaussians, scene.camera, splat::images_only(), pool);
  f.means2d.clear();
  EXPECT_THROW(
      {
        try {
          splat::scalar_composite(f);
        } catch (const splat::Error& e) {
          EXPECT_NE(std::string(e.what()).find("no intermediates"), std::string::npos) << e.what();
          throw;
        }
      },
      splat::Error);
}

// The shaders composite their own projection's splats exactly as the oracle does: alpha,
// transmittance and the last contributors bit for bit, cut-offs included.
TEST(CompositeOracle, VulkanForwardMatchesTheScalarOracleBitForBit) {
  GSLAM_REQUIRE_BACKEND(gpu, "vulkan");
  for (uint32_t seed = 1; seed <= 4; ++seed) {
    const auto scene = gslam::test::make_random_scene<float>(dense_scene(seed));
    const splat::ForwardResult f = gpu.forward(scene.gaussians, scene.camera, {});
    splat::ForwardResult oracle = f;
    splat::scalar_composite(oracle);
    // Colour and depth are sums of up to a few hundred terms in [0, 5]: fused against unfused
    // multiply-adds part them by a few float ulps of 5 m.
    expect_same_images(f, oracle, "vulkan, seed " + std::to_string(seed), 1e-5f);
  }
}

// The backward shaders against the oracle's gradients on the same forward result.
TEST(CompositeOracle, VulkanBackwardMatchesTheScalarOracle) {
  GSLAM_REQUIRE_BACKEND(gpu, "vulkan");
  splat::ThreadPool pool(2);
  SceneOptions o = dense_scene(3);
  o.min_opacity = 0.3;  // the parity rule's smooth scenes: no gradient decided at a cut-off
  o.max_opacity = 0.8;
  o.count = 60;
  const auto scene = gslam::test::make_random_scene<float>(o);
  const splat::ForwardResult f = gpu.forward(scene.gaussians, scene.camera, {});
  const splat::ImageGrads d = random_image_grads(f, 5);
  const splat::BackwardResult oracle = splat::scalar_reference_backward<float>(f, d, pool);
  const splat::BackwardResult ours = gpu.backward(f, d);
  gslam::test::expect_backward_parity(oracle, ours, "vulkan against the oracle");
}

}  // namespace
