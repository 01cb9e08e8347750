// The Vulkan backend's resident map (runs on lavapipe in CI): its bookkeeping against the host
// copy it was given, one mapping step against the same step done on the host (the backend's
// own forward and backward, the CPU losses, Adam), and what crosses the bus per step.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numeric>

#include "splat/adam.h"
#include "splat/error.h"
#include "splat/losses.h"
#include "splat/resident_map.h"
#include "support/backends.h"
#include "support/random_scene.h"

namespace {

using gslam::test::SceneOptions;

gslam::test::Scene<float> scene(int count, int width, int height, uint32_t seed) {
  SceneOptions o;
  o.seed = seed;
  o.count = count;
  o.sh_degree = 1;
  o.width = width;
  o.height = height;
  o.min_scale = 0.02;
  o.max_scale = 0.08;
  return gslam::test::make_random_scene<float>(o);
}

// A frame to fit: another random scene rendered at the same camera, with depth holes.
splat::RgbdFrame target_frame(splat::Rasterizer& rasterizer, const splat::Camera& camera, int count) {
  const gslam::test::Scene<float> other = scene(count, camera.width, camera.height, 99);
  const splat::ForwardResult render = rasterizer.forward(other.gaussians, camera, splat::images_only());
  splat::RgbdFrame f;
  f.camera = camera;
  f.rgb = render.rgb;
  f.depth = render.depth_normalized;
  for (std::size_t p = 0; p < f.depth.size(); p += 7) f.depth[p] = 0;
  return f;
}

std::size_t map_bytes(const splat::Gaussians& g) {
  return (g.means.size() + g.log_scales.size() + g.rotations.size() + g.opacity_logits.size() + g.sh.size()) * 4;
}

#define GSLAM_REQUIRE_RESIDENT(var, rasterizer, degree)               \
  GSLAM_REQUIRE_BACKEND(rasterizer, "vulkan");                        \
  std::unique_ptr<splat::ResidentMap> var = rasterizer.make_resident_map(degree); \
  ASSERT_TRUE(var) << "the Vulkan backend keeps maps on the device"

TEST(ResidentMap, KeepsWhatItIsGivenThroughAppendsAndPruning) {
  GSLAM_REQUIRE_RESIDENT(device, rasterizer, 1);
  const gslam::test::Scene<float> a = scene(300, 64, 48, 1), b = scene(200, 64, 48, 2);
  device->assign(a.gaussians, nullptr);
  device->append(b.gaussians);
  ASSERT_EQ(device->size(), 500u);
  // Keep every third Gaussian, across the boundary between the two.
  std::vector<uint8_t> keep(500, 0);
  splat::Gaussians expected;
  expected.sh_degree = 1;
  for (std::size_t i = 0; i < 500; i += 3) {
    keep[i] = 1;
    const splat::Gaussians& from = i < 300 ? a.gaussians : b.gaussians;
    const std::size_t j = i < 300 ? i : i - 300;
    const std::size_t k = expected.size();
    expected.resize(k + 1);
    for (splat::ParamGroup group : splat::kAllParamGroups) {
      const std::size_t width = static_cast<std::size_t>(splat::param_group_width(group, 1));
      for (std::size_t c = 0; c < width; ++c) splat::param_group(expected, group)[k * width + c] = splat::param_group(from, group)[j * width + c];
    }
  }
  device->keep(keep);
  splat::Gaussians read;
  splat::AdamMoments moments;
  device->read(read, &moments);
  ASSERT_EQ(read.size(), expected.size());
  for (splat::ParamGroup group : splat::kAllParamGroups) {
    EXPECT_EQ(splat::param_group(read, group), splat::param_group(expected, group)) << splat::param_group_name(group);
    EXPECT_EQ(device->read_group(group), splat::param_group(expected, group)) << splat::param_group_name(group);
    for (float m : splat::param_group(moments.m, group)) ASSERT_EQ(m, 0.f) << "appended Gaussians start with zero moments";
  }
  EXPECT_EQ(moments.steps, std::vector<uint32_t>(expected.size(), 0u));
  // Its renders are the backend's renders of the map it holds; coverage brings back two images.
  const splat::ForwardResult host = rasterizer.forward(expected, a.camera, splat::images_only());
  const splat::ForwardResult all = device->render(a.camera, splat::images_only(), false);
  const splat::ForwardResult coverage = device->render(a.camera, splat::images_only(), true);
  EXPECT_EQ(all.rgb, host.rgb);
  EXPECT_EQ(all.depth, host.depth);
  EXPECT_EQ(coverage.alpha, host.alpha);
  EXPECT_EQ(coverage.depth_normalized, host.depth_normalized);
  EXPECT_TRUE(coverage.rgb.empty() && coverage.depth.empty());
  EXPECT_THROW(device->keep(std::vector<uint8_t>(3, 1)), splat::Error) << "one flag per Gaussian";
  SceneOptions degree0;
  degree0.sh_degree = 0;
  EXPECT_THROW(device->append(gslam::test::make_random_scene<float>(degree0).gaussians), splat::Error)
      << "SH degree 0 into a degree-1 map";
}

TEST(ResidentMap, RefusesUnknownTargetsWrongSizesAndAnEmptyMap) {
  GSLAM_REQUIRE_RESIDENT(device, rasterizer, 1);
  const gslam::test::Scene<float> s = scene(50, 64, 48, 4);
  const splat::MappingLoss loss;
  const splat::AdamRates rates;
  EXPECT_THROW(device->step(0, s.camera, loss, rates, 1, false), splat::Error) << "empty map";
  device->assign(s.gaussians, nullptr);
  EXPECT_THROW(device->step(7, s.camera, loss, rates, 1, false), splat::Error) << "no target 7";
  splat::RgbdFrame frame = target_frame(rasterizer, s.camera, 50);
  device->set_target(7, frame);
  EXPECT_TRUE(device->has_target(7));
  splat::Camera larger = s.camera;
  larger.width = 80;
  EXPECT_THROW(device->step(7, larger, loss, rates, 1, false), splat::Error) << "camera of another size";
  frame.depth.pop_back();
  EXPECT_THROW(device->set_target(8, frame), splat::Error) << "depth of the wrong size";
  splat::RgbdFrame huge;
  huge.camera = s.camera;
  huge.camera.width = huge.camera.height = 4200;
  EXPECT_THROW(device->set_target(9, huge), splat::Error) << "more pixels than the loss's workgroups cover";
  splat::AdamMoments moments{s.gaussians, s.gaussians, std::vector<uint32_t>(s.gaussians.size(), 1)};
  moments.v.sh_degree = 0;
  EXPECT_THROW(device->assign(s.gaussians, &moments), splat::Error) << "moments of another SH degree";
  EXPECT_EQ(device->size(), s.gaussians.size()) << "a refused assign leaves the map";
  device->drop_target(7);
  EXPECT_FALSE(device->has_target(7));
}

// The tests that run where the map is, against the same tests on the host's copy.
TEST(ResidentMap, FreeSpaceAndPruningTestsGiveTheHostsVerdicts) {
  GSLAM_REQUIRE_RESIDENT(device, rasterizer, 1);
  gslam::test::Scene<float> s = scene(2000, 64, 48, 6);
  for (std::size_t i = 0; i < s.gaussians.size(); i += 5) s.gaussians.opacity_logits[i] = -8;  // faint
  for (std::size_t i = 1; i < s.gaussians.size(); i += 7) s.gaussians.log_scales[i * 3 + 1] = 1;  // oversized
  splat::RgbdFrame frame = target_frame(rasterizer, s.camera, 400);
  frame.ignore.assign(frame.depth.size(), 0);
  for (std::size_t p = 0; p < frame.ignore.size(); p += 13) frame.ignore[p] = 1;
  device->assign(s.gaussians, nullptr);
  device->set_target(1, frame);
  const splat::ResidentMap::FreeSpaceTest test{0.1f, 0.05f, 0.02f};
  const std::size_t first = 500;
  const std::vector<splat::FreeSpace> verdicts = device->free_space_test(1, s.camera, first, test);
  ASSERT_EQ(verdicts.size(), s.gaussians.size() - first);
  const Eigen::Matrix3f r = s.camera.T_cam_world.linear().cast<float>();
  const Eigen::Vector3f t = s.camera.T_cam_world.translation().cast<float>();
  const int w = s.camera.width, h = s.camera.height;
  std::size_t differ = 0, through = 0, on = 0;
  for (std::size_t i = first; i < s.gaussians.size(); ++i) {
    const float* m = &s.gaussians.means[i * 3];
    const Eigen::Vector3f p = r * Eigen::Vector3f(m[0], m[1], m[2]) + t;
    splat::FreeSpace want = splat::FreeSpace::kNone;
    const float u = float(s.camera.fx) * p.x() / p.z() + float(s.camera.cx), v = float(s.camera.fy) * p.y() / p.z() + float(s.camera.cy);
    if (p.z() > test.near_z && u >= 1 && v >= 1 && u < float(w - 1) && v < float(h - 1)) {
      const float margin = test.margin + test.margin_per_metre * p.z();
      bool all_through = true, any_on = false, measured = true;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const std::size_t k = std::size_t(int(v) + dy) * std::size_t(w) + std::size_t(int(u) + dx);
          measured = measured && frame.depth[k] > 0 && !frame.ignore[k];
          all_through = all_through && frame.depth[k] > p.z() + margin;
          any_on = any_on || std::abs(frame.depth[k] - p.z()) <= margin;
        }
      }
      if (measured) want = all_through ? splat::FreeSpace::kThrough : any_on ? splat::FreeSpace::kOn : splat::FreeSpace::kNone;
    }
    differ += verdicts[i - first] != want;
    through += want == splat::FreeSpace::kThrough;
    on += want == splat::FreeSpace::kOn;
  }
  EXPECT_GT(through, 20u) << "the scene has centres in front of the frame's surface";
  EXPECT_GT(on, 20u) << "and on it";
  // A centre exactly at a margin or a pixel edge may fall either way with the order of rounding
  // (the host's compiler may fuse multiply-adds): at most one in 500.
  EXPECT_LE(differ, verdicts.size() / 500) << differ << " of " << verdicts.size() << " verdicts differ";

  const float min_logit = -5.3f, max_log_scale = -0.7f;
  const std::vector<uint8_t> flags = device->faint_or_oversized(min_logit, max_log_scale);
  ASSERT_EQ(flags.size(), s.gaussians.size());
  std::size_t flagged = 0;
  for (std::size_t i = 0; i < flags.size(); ++i) {
    const float* ls = &s.gaussians.log_scales[i * 3];
    const bool want = s.gaussians.opacity_logits[i] < min_logit || std::max({ls[0], ls[1], ls[2]}) > max_log_scale;
    ASSERT_EQ(bool(flags[i]), want) << "Gaussian " << i;
    flagged += want;
  }
  EXPECT_GT(flagged, s.gaussians.size() / 4);
  EXPECT_LT(flagged, s.gaussians.size() / 2);
}

// Densification's coverage test on the device against the host's, computed from the device's
// own render of the map: the median depth error (radix selection on the device) and the mask.
// The target is another scene, so the map covers some pixels, misses others, and lies behind
// the measured depth at some.
TEST(ResidentMap, CoverageMaskGivesTheHostsMask) {
  GSLAM_REQUIRE_RESIDENT(device, rasterizer, 1);
  const gslam::test::Scene<float> s = scene(300, 64, 48, 7);
  splat::RgbdFrame frame = target_frame(rasterizer, s.camera, 400);
  frame.ignore.assign(frame.depth.size(), 0);
  for (std::size_t p = 0; p < frame.ignore.size(); p += 11) frame.ignore[p] = 1;
  device->assign(s.gaussians, nullptr);
  device->set_target(3, frame);
  const splat::ResidentMap::CoverageTest test{0.5f, 2.0f, 1e-3f};
  const std::vector<uint8_t> mask = device->coverage_mask(3, s.camera, test);
  const splat::ForwardResult render = device->render(s.camera, splat::images_only(), true);
  ASSERT_EQ(mask.size(), frame.depth.size());
  std::vector<float> errors;
  for (std::size_t p = 0; p < frame.depth.size(); ++p) {
    if (frame.depth[p] > 0 && render.alpha[p] > test.densify_alpha) errors.push_back(std::abs(render.depth_normalized[p] - frame.depth[p]));
  }
  ASSERT_GT(errors.size(), 100u) << "the map covers measured pixels";
  std::nth_element(errors.begin(), errors.begin() + static_cast<long>(errors.size() / 2), errors.end());
  const float threshold = test.depth_error_factor * std::max(errors[errors.size() / 2], test.min_median);
  std::size_t uncovered = 0, in_front = 0, differ = 0, seeded = 0;
  for (std::size_t p = 0; p < mask.size(); ++p) {
    const bool open = render.alpha[p] < test.densify_alpha;
    const bool front = frame.depth[p] > 0 && render.depth_normalized[p] - frame.depth[p] > threshold;
    const bool want = (open || front) && !frame.ignore[p];
    uncovered += open && !frame.ignore[p];
    in_front += front && !open && !frame.ignore[p];
    differ += bool(mask[p]) != want;
    seeded += want;
  }
  EXPECT_GT(uncovered, 50u) << "the map leaves pixels uncovered";
  EXPECT_GT(in_front, 20u) << "and lies behind the measured depth at others";
  EXPECT_LT(seeded, mask.size() * 9 / 10) << "but not everywhere";
  // Exactly, but for a pixel whose error lies exactly at the threshold (the host's compiler may
  // fuse the subtraction into the comparison): at most one in 500.
  EXPECT_LE(differ, mask.size() / 500) << differ << " of " << mask.size() << " pixels differ";
  EXPECT_THROW(device->coverage_mask(4, s.camera, test), splat::Error) << "no frame stored under 4";
}

// The step on the device against the same step on the host: the backend's forward and
// backward of the host's map, the CPU losses and splat::adam_update.
TEST(ResidentMap, StepMatchesTheHostLoopAndMovesOnlyScalars) {
  GSLAM_REQUIRE_RESIDENT(device, rasterizer, 1);
  const gslam::test::Scene<float> s = scene(3000, 64, 48, 5);
  splat::RgbdFrame frame = target_frame(rasterizer, s.camera, 400);
  frame.ignore.assign(frame.depth.size(), 0);
  for (std::size_t p = 0; p < frame.ignore.size(); p += 11) frame.ignore[p] = 1;
  splat::MappingLoss loss;
  loss.vignetting_k1 = 0.05;
  loss.vignetting_k2 = -0.02;
  splat::AdamRates rates;
  rates.means = 1e-3, rates.log_scales = 5e-3, rates.rotations = 1e-3, rates.opacity_logits = 5e-2;
  rates.sh_dc = 2.5e-3, rates.sh_rest = 1.25e-4;
  const double lr_scale = 0.5;

  // The host step.
  splat::Gaussians host = s.gaussians;
  const splat::ForwardResult render = rasterizer.forward(host, s.camera, splat::images_only());
  const std::size_t pixels = frame.depth.size();
  std::vector<float> recorded = render.rgb, gain(pixels);
  for (int y = 0; y < s.camera.height; ++y) {
    for (int x = 0; x < s.camera.width; ++x) {
      const double u = (x + 0.5 - s.camera.cx) / s.camera.fx, v = (y + 0.5 - s.camera.cy) / s.camera.fy, r2 = u * u + v * v;
      const std::size_t p = std::size_t(y) * s.camera.width + x;
      gain[p] = float(1 + r2 * (loss.vignetting_k1 + r2 * loss.vignetting_k2));
      for (int c = 0; c < 3; ++c) recorded[p * 3 + c] *= gain[p];
    }
  }
  std::vector<float> target_rgb = frame.rgb, target_depth = frame.depth;
  for (std::size_t p = 0; p < pixels; ++p) {
    if (!frame.ignore[p]) continue;
    for (int c = 0; c < 3; ++c) target_rgb[p * 3 + c] = recorded[p * 3 + c];
    target_depth[p] = 0;
  }
  splat::ImageGrads d;
  d.rgb.assign(pixels * 3, 0.f);
  d.alpha.assign(pixels, 0.f);
  d.depth.assign(pixels, 0.f);
  double host_loss = splat::l1_loss<float>(recorded, target_rgb, 3, {}, d.rgb, loss.color_weight);
  host_loss += splat::dssim_loss<float>(recorded, target_rgb, s.camera.width, s.camera.height, 3, d.rgb, loss.ssim_weight);
  for (std::size_t p = 0; p < pixels; ++p)
    for (int c = 0; c < 3; ++c) d.rgb[p * 3 + c] *= gain[p];
  host_loss += splat::silhouette_depth_l1_loss<float>(render.depth, render.alpha, target_depth, loss.depth_alpha_threshold,
                                                      d.depth, d.alpha, loss.depth_weight);
  const splat::BackwardResult grads = rasterizer.backward(render, d);
  const double rate[] = {rates.means, rates.log_scales, rates.rotations, rates.opacity_logits};
  for (splat::ParamGroup group : splat::kAllParamGroups) {
    std::vector<float>& p = splat::param_group(host, group);
    const std::vector<float>& g = splat::param_group(grads.d_gaussians, group);
    const std::size_t width = static_cast<std::size_t>(splat::param_group_width(group, 1));
    for (std::size_t k = 0; k < p.size(); ++k) {
      float m = 0, v = 0;
      const double lr = group == splat::ParamGroup::kSh ? (k % width < 3 ? rates.sh_dc : rates.sh_rest)
                                                         : rate[static_cast<int>(group)];
      splat::adam_update(p[k], g[k], m, v, lr * lr_scale, 1 - rates.hyper.beta1, 1 - rates.hyper.beta2, rates.hyper);
    }
  }

  // The device step.
  device->assign(s.gaussians, nullptr);
  device->set_target(3, frame);
  rasterizer.reset_transfers();
  const splat::MappingStepResult step = device->step(3, s.camera, loss, rates, lr_scale, false);
  const splat::Rasterizer::Transfers moved = rasterizer.transfers();
  EXPECT_NEAR(step.loss, host_loss, 1e-5 * host_loss);
  EXPECT_LT((step.d_loss_d_pose - grads.d_loss_d_pose).norm(), 1e-3 * grads.d_loss_d_pose.norm() + 1e-6);
  splat::Gaussians stepped;
  device->read(stepped, nullptr);
  // Adam's first step moves a parameter by about its rate, whatever the gradient's size: a step
  // whose gradient differs only by float rounding may still flip a tiny gradient's sign. So:
  // nearly every value agrees to 1% of its rate, and none is off by more than twice its rate.
  for (splat::ParamGroup group : splat::kAllParamGroups) {
    const std::vector<float>& want = splat::param_group(host, group);
    const std::vector<float>& got = splat::param_group(stepped, group);
    const std::vector<float>& before = splat::param_group(s.gaussians, group);
    std::size_t agree = 0, moved_values = 0;
    for (std::size_t k = 0; k < want.size(); ++k) {
      const double step_size = std::abs(double(want[k]) - before[k]);
      moved_values += step_size > 0;
      ASSERT_LE(std::abs(double(got[k]) - want[k]), 2.01 * std::max(step_size, 1e-7) + 1e-6)
          << splat::param_group_name(group) << " value " << k;
      agree += std::abs(double(got[k]) - want[k]) <= 0.01 * step_size + 1e-6;
    }
    EXPECT_GT(moved_values, want.size() / 4) << splat::param_group_name(group) << ": the step moved the map";
    EXPECT_GE(double(agree), 0.99 * double(want.size())) << splat::param_group_name(group);
  }
  // Per step: the frame's parameters, the intersection count, Adam's and the loss's constants,
  // and the loss terms and pose gradient summed on the device; nothing map- or image-sized.
  const std::size_t bytes = moved.to_device + moved.to_host;
  std::printf("resident step: %zu bytes up, %zu down; the map is %zu bytes\n", moved.to_device, moved.to_host,
              map_bytes(s.gaussians));
  EXPECT_LE(double(bytes), 0.01 * double(map_bytes(s.gaussians)));
  EXPECT_LE(bytes, 1024u) << "a few scalars, whatever the map's and the image's sizes";
}

}  // namespace
