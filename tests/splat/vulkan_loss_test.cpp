// The mapping loss on the device (MappingLossKernels) against the CPU's composition of it in
// mapping::Mapper::optimize_step, recomputed here in double from splat's losses: L1 and D-SSIM
// of the vignetted render, ignored pixels, silhouette depth L1, and the gradient through the
// vignetting. Runs on any Vulkan device (lavapipe in CI); skipped without one unless
// GSLAM_REQUIRE_GPU_TESTS makes that a failure.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "splat/error.h"
#include "splat/losses.h"
#include "support/backends.h"
#include "support/expect_error.h"
#include "vulkan/context.h"
#include "vulkan/mapping_loss.h"

namespace {

using splat::vk::Buffer;
using splat::vk::CommandBatch;
using splat::vk::Context;

// Tolerances against the double reference:
// The loss: float inputs, per-pixel terms in float, sums in double; 1 - mean SSIM of random
// images is ~0.5, so float SSIM terms (relative error ~1e-6) keep it well within this.
constexpr double kLossRtol = 1e-5;
// d_rgb, relative to the largest reference gradient: the D-SSIM gradient is computed in float
// through two 121-tap blurs and E[x^2] - mu_x^2 (which cancels about one digit of float's seven).
constexpr double kRgbGradTol = 1e-5;
// d_alpha, d_depth: computed in double from the same float inputs, then rounded to float.
constexpr double kDepthGradRtol = 1e-6;
// dL/dk: sums of d_gain r^2 whose terms carry the d_rgb error above and partly cancel.
constexpr double kVignettingRtol = 1e-4;

// One Vulkan context per variant for the whole test process (creating one is slow), or null
// with the reason. Released after the last test, while the drivers are still loaded.
std::map<bool, std::pair<std::unique_ptr<Context>, std::string>> contexts;

class ReleaseContexts : public ::testing::Environment {
 public:
  void TearDown() override { contexts.clear(); }
};
[[maybe_unused]] ::testing::Environment* const release_contexts =
    ::testing::AddGlobalTestEnvironment(new ReleaseContexts);

// mapped: host reads and writes device memory in place where it can (lavapipe); otherwise
// every transfer goes through staging copies, as on a discrete GPU.
Context* shared_context(bool mapped, std::string& why_not) {
  auto it = contexts.find(mapped);
  if (it == contexts.end()) {
    std::pair<std::unique_ptr<Context>, std::string> entry;
    try {
      splat::VulkanOptions options;
      options.map_device_memory = mapped;
      entry.first = std::make_unique<Context>(options);
    } catch (const splat::Error& e) {
      entry.second = e.what();
    }
    it = contexts.emplace(mapped, std::move(entry)).first;
  }
  why_not = it->second.second;
  return it->second.first.get();
}

#define GSLAM_REQUIRE_CONTEXT(var, mapped)                                                    \
  std::string var##_why_not;                                                                  \
  Context* var##_ptr = shared_context(mapped, var##_why_not);                                 \
  if (!var##_ptr) {                                                                           \
    if (::gslam::test::gpu_tests_required()) FAIL() << "no Vulkan device: " << var##_why_not; \
    GTEST_SKIP() << "no Vulkan device: " << var##_why_not;                                    \
  }                                                                                           \
  Context& var = *var##_ptr

// A render and its target, as the mapper sees them.
struct LossInputs {
  splat::Camera camera;
  std::vector<float> rgb, alpha, depth;  // [H, W, 3], [H, W], [H, W]
  std::vector<float> target_rgb, target_depth;
  std::vector<uint32_t> ignore;  // [H, W] or empty
  std::size_t measured = 0;      // target depth > 0 and not ignored
};

// Random render and target: colours near each other (SSIM well inside (0, 1)), a flat block
// equal in both (near-zero variance), silhouettes on both sides of the depth threshold, depth
// holes, and (with `ignoring`) an ignored rectangle plus scattered ignored pixels.
LossInputs random_inputs(uint32_t seed, int width, int height, bool ignoring, bool holes_only) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  LossInputs in;
  in.camera.width = width;
  in.camera.height = height;
  in.camera.fx = 0.9 * width;
  in.camera.fy = 0.85 * width;
  in.camera.cx = 0.5 * width + 1.3;
  in.camera.cy = 0.5 * height - 0.7;
  const std::size_t pixels = std::size_t(width) * std::size_t(height);
  for (std::size_t p = 0; p < pixels; ++p) {
    const int x = int(p % std::size_t(width)), y = int(p / std::size_t(width));
    const bool flat = x < 6 && y < 6;
    for (int c = 0; c < 3; ++c) {
      const float v = flat ? 0.3f : u(rng);
      in.rgb.push_back(v);
      in.target_rgb.push_back(flat ? v : std::clamp(v + 0.3f * (u(rng) - 0.5f), 0.f, 1.f));
    }
    const float a = u(rng) < 0.3f ? 0.96f + 0.04f * u(rng) : 0.2f + 0.75f * u(rng);
    const float z = 1.f + 3.f * u(rng);
    in.alpha.push_back(a);
    in.depth.push_back(a * z);
    const bool hole = holes_only || u(rng) < 0.2f;
    in.target_depth.push_back(hole ? 0.f : z + 0.2f * (u(rng) - 0.5f));
    if (ignoring) {
      const bool block = x >= width / 4 && x < width / 2 && y >= height / 3 && y < 2 * height / 3;
      in.ignore.push_back(block || u(rng) < 0.05f ? 1u : 0u);
    }
    const bool ignored = ignoring && in.ignore.back() != 0;
    if (in.target_depth.back() > 0 && !ignored) ++in.measured;
  }
  return in;
}

struct LossOutputs {
  double loss = 0;
  std::array<double, 2> d_vignetting = {0, 0};
  std::vector<double> d_rgb, d_alpha, d_depth;
};

// Mapper::optimize_step's loss in double: the render through the vignetting, ignored pixels'
// targets replaced, l1_loss + dssim_loss of the recorded colour, the vignetting backward, then
// silhouette_depth_l1_loss.
LossOutputs cpu_reference(const LossInputs& in, const splat::MappingLoss& loss) {
  const splat::Camera& cam = in.camera;
  const std::size_t pixels = std::size_t(cam.width) * std::size_t(cam.height);
  std::vector<double> rgb(in.rgb.begin(), in.rgb.end()), gain(pixels), r2(pixels);
  std::vector<double> recorded(pixels * 3);
  for (std::size_t p = 0; p < pixels; ++p) {
    const double u = (double(p % std::size_t(cam.width)) + 0.5 - cam.cx) / cam.fx;
    const double v = (double(p / std::size_t(cam.width)) + 0.5 - cam.cy) / cam.fy;
    r2[p] = u * u + v * v;
    gain[p] = 1 + r2[p] * (loss.vignetting_k1 + r2[p] * loss.vignetting_k2);
    for (int c = 0; c < 3; ++c) recorded[p * 3 + c] = rgb[p * 3 + c] * gain[p];
  }
  std::vector<double> target_rgb(in.target_rgb.begin(), in.target_rgb.end());
  std::vector<double> target_depth(in.target_depth.begin(), in.target_depth.end());
  for (std::size_t p = 0; p < in.ignore.size(); ++p) {
    if (!in.ignore[p]) continue;
    for (int c = 0; c < 3; ++c) target_rgb[p * 3 + c] = recorded[p * 3 + c];
    target_depth[p] = 0;
  }
  LossOutputs out;
  std::vector<double> d_recorded(pixels * 3, 0.0);
  out.loss = splat::l1_loss<double>(recorded, target_rgb, 3, {}, d_recorded, loss.color_weight);
  if (loss.ssim_weight > 0) {
    out.loss += splat::dssim_loss<double>(recorded, target_rgb, cam.width, cam.height, 3,
                                          d_recorded, loss.ssim_weight);
  }
  out.d_rgb.resize(pixels * 3);
  for (std::size_t p = 0; p < pixels; ++p) {
    double d_gain = 0;  // dL/d(gain)
    for (int c = 0; c < 3; ++c) {
      d_gain += d_recorded[p * 3 + c] * rgb[p * 3 + c];
      out.d_rgb[p * 3 + c] = d_recorded[p * 3 + c] * gain[p];
    }
    out.d_vignetting[0] += d_gain * r2[p];
    out.d_vignetting[1] += d_gain * r2[p] * r2[p];
  }
  std::vector<double> depth(in.depth.begin(), in.depth.end());
  std::vector<double> alpha(in.alpha.begin(), in.alpha.end());
  out.d_depth.assign(pixels, 0.0);
  out.d_alpha.assign(pixels, 0.0);
  out.loss += splat::silhouette_depth_l1_loss<double>(depth, alpha, target_depth,
                                                      loss.depth_alpha_threshold, out.d_depth,
                                                      out.d_alpha, loss.depth_weight);
  return out;
}

Buffer upload(Context& context, CommandBatch& batch, const void* data, std::size_t bytes) {
  Buffer b(context);
  b.reserve(bytes);
  batch.upload(b, data, bytes);
  return b;
}

// The device's loss of `in`; `kernels` may be reused across calls.
LossOutputs device_loss(Context& context, splat::vk::MappingLossKernels& kernels,
                        const LossInputs& in, const splat::MappingLoss& loss) {
  CommandBatch batch(context);
  const std::size_t pixels = in.alpha.size();
  Buffer rgb = upload(context, batch, in.rgb.data(), pixels * 12);
  Buffer alpha = upload(context, batch, in.alpha.data(), pixels * 4);
  Buffer depth = upload(context, batch, in.depth.data(), pixels * 4);
  Buffer target_rgb = upload(context, batch, in.target_rgb.data(), pixels * 12);
  Buffer target_depth = upload(context, batch, in.target_depth.data(), pixels * 4);
  Buffer ignore(context), d_rgb(context), d_alpha(context), d_depth(context);
  if (!in.ignore.empty()) ignore = upload(context, batch, in.ignore.data(), pixels * 4);
  d_rgb.reserve(pixels * 12);
  d_alpha.reserve(pixels * 4);
  d_depth.reserve(pixels * 4);
  // Garbage in the gradient buffers: the kernels overwrite them.
  const std::vector<float> junk(pixels * 3, 7.f);
  batch.upload(d_rgb, junk.data(), pixels * 12);
  batch.upload(d_alpha, junk.data(), pixels * 4);
  batch.upload(d_depth, junk.data(), pixels * 4);
  splat::vk::LossBuffers buffers;
  buffers.rgb = &rgb;
  buffers.alpha = &alpha;
  buffers.depth = &depth;
  buffers.target_rgb = &target_rgb;
  buffers.target_depth = &target_depth;
  buffers.ignore = in.ignore.empty() ? nullptr : &ignore;
  buffers.d_rgb = &d_rgb;
  buffers.d_alpha = &d_alpha;
  buffers.d_depth = &d_depth;
  kernels.record(batch, buffers, in.camera, loss, in.measured);
  std::vector<float> g_rgb(pixels * 3), g_alpha(pixels), g_depth(pixels);
  batch.download(d_rgb, g_rgb.data(), pixels * 12);
  batch.download(d_alpha, g_alpha.data(), pixels * 4);
  batch.download(d_depth, g_depth.data(), pixels * 4);
  batch.run();
  const auto r = kernels.result();
  LossOutputs out;
  out.loss = r.loss;
  out.d_vignetting = r.d_vignetting;
  out.d_rgb.assign(g_rgb.begin(), g_rgb.end());
  out.d_alpha.assign(g_alpha.begin(), g_alpha.end());
  out.d_depth.assign(g_depth.begin(), g_depth.end());
  return out;
}

std::string scientific(double v) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.2e", v);
  return text;
}

double max_abs(const std::vector<double>& v) {
  double m = 0;
  for (double x : v) m = std::max(m, std::abs(x));
  return m;
}

// Compares every output; `what` names the case in every message.
void expect_matches(const LossOutputs& gpu, const LossOutputs& cpu, const std::string& what) {
  EXPECT_NEAR(gpu.loss, cpu.loss, kLossRtol * std::abs(cpu.loss)) << what;
  const double rgb_tol = kRgbGradTol * max_abs(cpu.d_rgb);
  double worst_rgb = 0, worst_depth = 0;
  for (std::size_t i = 0; i < cpu.d_rgb.size(); ++i) {
    const double e = std::abs(gpu.d_rgb[i] - cpu.d_rgb[i]);
    worst_rgb = std::max(worst_rgb, e / max_abs(cpu.d_rgb));
    EXPECT_LE(e, rgb_tol) << what << ": d_rgb " << i << " gpu " << gpu.d_rgb[i] << " cpu "
                          << cpu.d_rgb[i];
  }
  for (std::size_t p = 0; p < cpu.d_depth.size(); ++p) {
    const double e_depth = std::abs(gpu.d_depth[p] - cpu.d_depth[p]);
    const double e_alpha = std::abs(gpu.d_alpha[p] - cpu.d_alpha[p]);
    worst_depth = std::max({worst_depth, e_depth / std::max(std::abs(cpu.d_depth[p]), 1e-30),
                            e_alpha / std::max(std::abs(cpu.d_alpha[p]), 1e-30)});
    EXPECT_LE(e_depth, kDepthGradRtol * std::abs(cpu.d_depth[p]))
        << what << ": d_depth " << p << " gpu " << gpu.d_depth[p] << " cpu " << cpu.d_depth[p];
    EXPECT_LE(e_alpha, kDepthGradRtol * std::abs(cpu.d_alpha[p]))
        << what << ": d_alpha " << p << " gpu " << gpu.d_alpha[p] << " cpu " << cpu.d_alpha[p];
  }
  for (int k = 0; k < 2; ++k) {
    EXPECT_NEAR(gpu.d_vignetting[k], cpu.d_vignetting[k],
                kVignettingRtol * std::abs(cpu.d_vignetting[k]))
        << what << ": dL/dk" << k + 1;
  }
  // The errors measured, for the test's XML report.
  ::testing::Test::RecordProperty(what + "_loss_rel_err",
                                  scientific(std::abs(gpu.loss - cpu.loss) / std::abs(cpu.loss)));
  ::testing::Test::RecordProperty(what + "_d_rgb_err_over_max", scientific(worst_rgb));
  ::testing::Test::RecordProperty(what + "_d_depth_alpha_rel_err", scientific(worst_depth));
  for (int k = 0; k < 2; ++k) {
    ::testing::Test::RecordProperty(what + "_dk" + std::to_string(k + 1) + "_rel_err",
                                    scientific(std::abs(gpu.d_vignetting[k] - cpu.d_vignetting[k]) /
                                               std::abs(cpu.d_vignetting[k])));
  }
}

splat::MappingLoss mapping_loss(double ssim_weight, double k1, double k2) {
  splat::MappingLoss loss;
  loss.color_weight = 0.5;
  loss.ssim_weight = ssim_weight;
  loss.depth_weight = 1.0;
  loss.depth_alpha_threshold = 0.95;
  loss.vignetting_k1 = k1;
  loss.vignetting_k2 = k2;
  return loss;
}

// Runs `loss` on both image sizes (one not a multiple of the workgroup, one that is).
void check_case(Context& context, const splat::MappingLoss& loss, bool ignoring,
                bool holes_only = false) {
  splat::vk::MappingLossKernels kernels(context);
  const std::array<std::array<int, 2>, 2> sizes = {{{37, 29}, {64, 48}}};
  uint32_t seed = 11;
  for (const auto& [w, h] : sizes) {
    const LossInputs in = random_inputs(seed++, w, h, ignoring, holes_only);
    const std::string what = std::to_string(w) + "x" + std::to_string(h);
    expect_matches(device_loss(context, kernels, in, loss), cpu_reference(in, loss), what);
  }
}

TEST(VulkanLoss, MatchesCpuWithoutVignettingOrIgnoredPixels) {
  GSLAM_REQUIRE_CONTEXT(context, true);
  check_case(context, mapping_loss(0.2, 0, 0), false);
}

TEST(VulkanLoss, MatchesCpuWithVignettingAndIgnoredPixels) {
  GSLAM_REQUIRE_CONTEXT(context, true);
  check_case(context, mapping_loss(0.2, -0.25, 0.08), true);
}

TEST(VulkanLoss, MatchesCpuWithoutDssim) {
  GSLAM_REQUIRE_CONTEXT(context, true);
  check_case(context, mapping_loss(0, 0.15, -0.05), true);
  check_case(context, mapping_loss(0, 0, 0), false);
}

TEST(VulkanLoss, MatchesCpuWithVignettingAlone) {
  GSLAM_REQUIRE_CONTEXT(context, true);
  check_case(context, mapping_loss(0.1, 0.2, 0.03), false);
}

TEST(VulkanLoss, MatchesCpuWithIgnoredPixelsAlone) {
  GSLAM_REQUIRE_CONTEXT(context, true);
  check_case(context, mapping_loss(0.1, 0, 0), true);
}

TEST(VulkanLoss, NoMeasuredDepthLeavesOnlyTheColourTerms) {
  GSLAM_REQUIRE_CONTEXT(context, true);
  check_case(context, mapping_loss(0.1, -0.1, 0), true, true);
}

TEST(VulkanLoss, StagedTransfersMatchCpu) {
  GSLAM_REQUIRE_CONTEXT(context, false);
  check_case(context, mapping_loss(0.2, -0.25, 0.08), true);
}

TEST(VulkanLoss, RejectsMissingAndSmallBuffers) {
  GSLAM_REQUIRE_CONTEXT(context, true);
  splat::vk::MappingLossKernels kernels(context);
  const LossInputs in = random_inputs(3, 37, 29, false, false);
  CommandBatch batch(context);
  Buffer small(context);
  small.reserve(256);
  splat::vk::LossBuffers buffers;
  GSLAM_EXPECT_ERROR(kernels.record(batch, buffers, in.camera, mapping_loss(0.1, 0, 0), 0),
                     "MappingLossKernels::record", "no rgb buffer");
  buffers.rgb = &small;
  GSLAM_EXPECT_ERROR(kernels.record(batch, buffers, in.camera, mapping_loss(0.1, 0, 0), 0),
                     "rgb holds", "expected at least 12876");
}

}  // namespace
