// gsplat 1.5.3 golden vectors (from Brush): forward outputs and intermediates must match on
// every element within |ours - ref| <= 1e-5 + 1e-2 |ref|, Brush's own criterion.
#include <cmath>
#include <string>
#include <tuple>

#include <gtest/gtest.h>

#include "splat/cpu_reference.h"
#include "support/backends.h"
#include "support/golden_case.h"
#include "support/test_data.h"

namespace {

using gslam::test::GoldenCase;

// (backend, golden case file)
using GoldenParam = std::tuple<std::string, const char*>;
std::string golden_name(const ::testing::TestParamInfo<GoldenParam>& info) {
  std::string file = std::get<1>(info.param);
  return std::get<0>(info.param) + "_" + file.substr(0, file.find('.'));
}

class GoldenForward : public ::testing::TestWithParam<GoldenParam> {};

TEST_P(GoldenForward, MatchesGsplatRenderAndIntermediates) {
  GSLAM_REQUIRE_SHARED_DATA(path, std::string("gsplat_reference_render_brush/") + std::get<1>(GetParam()));
  GSLAM_REQUIRE_BACKEND(rasterizer, std::get<0>(GetParam()));
  const GoldenCase golden = gslam::test::load_golden_case(path);
  const auto frame = rasterizer.forward(golden.gaussians, golden.camera, {});
  const std::size_t pixels = static_cast<std::size_t>(golden.camera.width) * golden.camera.height;
  const auto& ref_img = golden.tensor("out_img").values;
  for (std::size_t p = 0; p < pixels; ++p) {
    for (int c = 0; c < 4; ++c) {
      const float ours = c < 3 ? frame.rgb[p * 3 + c] : frame.alpha[p];
      const float ref = ref_img[p * 4 + c];
      EXPECT_NEAR(ours, ref, gslam::test::kGoldenAtol + gslam::test::kGoldenRtol * std::abs(ref))
          << "pixel " << p % golden.camera.width << "," << p / golden.camera.width << " channel "
          << c;
    }
  }
  const auto& xys = golden.tensor("xys").values;
  const auto& conics = golden.tensor("conics").values;
  const auto& depths = golden.tensor("depths").values;
  for (std::size_t i = 0; i < golden.gaussians.size(); ++i) {
    if (frame.radii[i * 2] == 0 && frame.radii[i * 2 + 1] == 0) continue;  // culled: undefined
    for (int k = 0; k < 2; ++k) {
      EXPECT_NEAR(frame.means2d[i * 2 + k], xys[i * 2 + k],
                  gslam::test::kGoldenAtol + gslam::test::kGoldenRtol * std::abs(xys[i * 2 + k]))
          << "xys of Gaussian " << i << " axis " << k;
    }
    for (int k = 0; k < 3; ++k) {
      EXPECT_NEAR(frame.conics[i * 3 + k], conics[i * 3 + k],
                  gslam::test::kGoldenAtol + gslam::test::kGoldenRtol * std::abs(conics[i * 3 + k]))
          << "conic of Gaussian " << i << " element " << k;
    }
    EXPECT_NEAR(frame.depths[i], depths[i],
                gslam::test::kGoldenAtol + gslam::test::kGoldenRtol * std::abs(depths[i]))
        << "depth of Gaussian " << i;
  }
  EXPECT_GT(frame.stats.visible, 0u) << "golden scene rendered nothing";
}

class GoldenBackward : public ::testing::TestWithParam<GoldenParam> {};

// Feeds gsplat's dL/d(out_img) and compares every parameter gradient it computed.
TEST_P(GoldenBackward, MatchesGsplatParameterGradients) {
  GSLAM_REQUIRE_SHARED_DATA(path, std::string("gsplat_reference_render_brush/") + std::get<1>(GetParam()));
  GSLAM_REQUIRE_BACKEND(rasterizer, std::get<0>(GetParam()));
  const GoldenCase golden = gslam::test::load_golden_case(path);
  splat::RenderSettings settings;
  settings.sh_direction_gradient = false;  // gsplat's convention for these vectors
  const auto frame = rasterizer.forward(golden.gaussians, golden.camera, settings);
  const auto& v_img = golden.tensor("v_out_img").values;
  const std::size_t pixels = static_cast<std::size_t>(golden.camera.width) * golden.camera.height;
  splat::ImageGrads d_image;
  d_image.rgb.resize(pixels * 3);
  d_image.alpha.resize(pixels);
  for (std::size_t p = 0; p < pixels; ++p) {
    for (int c = 0; c < 3; ++c) d_image.rgb[p * 3 + c] = v_img[p * 4 + c];
    d_image.alpha[p] = v_img[p * 4 + 3];
  }
  const auto grads = rasterizer.backward(frame, d_image);
  const std::pair<splat::ParamGroup, const char*> groups[] = {
      {splat::ParamGroup::kMeans, "v_means"},
      {splat::ParamGroup::kLogScales, "v_scales"},
      {splat::ParamGroup::kRotations, "v_quats"},
      {splat::ParamGroup::kOpacityLogits, "v_opacities"},
      {splat::ParamGroup::kSh, "v_coeffs"}};
  for (const auto& [group, key] : groups) {
    const auto& ours = splat::param_group(grads.d_gaussians, group);
    const auto& ref = golden.tensor(key).values;
    ASSERT_EQ(ours.size(), ref.size()) << key;
    float largest = 0;
    for (std::size_t i = 0; i < ref.size(); ++i) {
      largest = std::max(largest, std::abs(ref[i]));
      EXPECT_NEAR(ours[i], ref[i], gslam::test::kGoldenAtol + gslam::test::kGoldenRtol * std::abs(ref[i]))
          << key << "[" << i << "]";
    }
    EXPECT_GT(largest, 0) << key << " is all zero in the golden file";
  }
}

const auto kGoldenParams =
    ::testing::Combine(::testing::ValuesIn(gslam::test::backend_names()),
                       ::testing::Values("tiny_case.safetensors", "basic_case.safetensors"));
INSTANTIATE_TEST_SUITE_P(BackendsAndCases, GoldenBackward, kGoldenParams, golden_name);
INSTANTIATE_TEST_SUITE_P(BackendsAndCases, GoldenForward, kGoldenParams, golden_name);

}  // namespace
