#include "support/parity.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace gslam::test {
namespace {

void expect_images_close(const std::vector<float>& ref, const std::vector<float>& ours, int width,
                         int channels, const char* name, const std::string& label) {
  ASSERT_EQ(ref.size(), ours.size()) << label << " " << name;
  int reported = 0;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    if (std::abs(ref[i] - ours[i]) <= kImageParity) continue;
    const std::size_t pixel = i / static_cast<std::size_t>(channels);
    ADD_FAILURE() << label << ": " << name << " at pixel (" << pixel % width << ", "
                  << pixel / width << ") channel " << i % channels << ": cpu " << ref[i]
                  << ", vulkan " << ours[i];
    if (++reported == 10) return;
  }
}

float largest_abs(const std::vector<float>& v) {
  float m = 0;
  for (float x : v) m = std::max(m, std::abs(x));
  return m;
}

}  // namespace

void expect_relative_parity(const std::vector<float>& ref, const std::vector<float>& ours,
                            const std::string& label) {
  ASSERT_EQ(ref.size(), ours.size()) << label;
  const float floor = kRelativeFloor * largest_abs(ref);
  int reported = 0;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    const float bound = kGradientParity * (std::abs(ref[i]) + floor);
    if (std::abs(ref[i] - ours[i]) <= bound) continue;
    ADD_FAILURE() << label << "[" << i << "]: cpu " << ref[i] << ", vulkan " << ours[i]
                  << " (bound " << bound << ")";
    if (++reported == 10) return;
  }
}

void expect_forward_parity(const splat::ForwardResult& cpu, const splat::ForwardResult& gpu,
                           bool stages, const std::string& label) {
  ASSERT_EQ(cpu.width, gpu.width) << label;
  ASSERT_EQ(cpu.height, gpu.height) << label;
  expect_images_close(cpu.rgb, gpu.rgb, cpu.width, 3, "rgb", label);
  expect_images_close(cpu.alpha, gpu.alpha, cpu.width, 1, "alpha", label);
  expect_images_close(cpu.depth, gpu.depth, cpu.width, 1, "depth", label);
  EXPECT_EQ(cpu.stats.visible, gpu.stats.visible) << label;
  if (!stages) return;
  expect_relative_parity(cpu.means2d, gpu.means2d, label + " means2d");
  expect_relative_parity(cpu.conics, gpu.conics, label + " conics");
  expect_relative_parity(cpu.depths, gpu.depths, label + " depths");
  expect_relative_parity(cpu.colors, gpu.colors, label + " colors");
  EXPECT_EQ(cpu.radii, gpu.radii) << label << " radii";
  EXPECT_EQ(cpu.stats.intersections, gpu.stats.intersections) << label;
  EXPECT_EQ(cpu.last_contributor, gpu.last_contributor) << label << " last contributor";
  // Each tile's front-to-back list (empty tiles' begin offsets may differ, their lists not).
  ASSERT_EQ(cpu.tile_ranges.size(), gpu.tile_ranges.size()) << label;
  for (std::size_t t = 0; t < cpu.tile_ranges.size() / 2; ++t) {
    const auto list = [&](const splat::ForwardResult& f) {
      return std::vector<uint32_t>(f.sorted_ids.begin() + f.tile_ranges[t * 2],
                                   f.sorted_ids.begin() + f.tile_ranges[t * 2 + 1]);
    };
    EXPECT_EQ(list(cpu), list(gpu)) << label << " tile " << t;
  }
}

void expect_backward_parity(const splat::BackwardResult& cpu, const splat::BackwardResult& gpu,
                            const std::string& label, GradientRule rule) {
  auto compare = [&](const std::vector<float>& ref, const std::vector<float>& ours,
                     const std::string& name) {
    if (rule == GradientRule::kElementwise) return expect_relative_parity(ref, ours, name);
    ASSERT_EQ(ref.size(), ours.size()) << name;
    double diff = 0, norm = 0;
    for (std::size_t i = 0; i < ref.size(); ++i) {
      diff += (double(ours[i]) - ref[i]) * (double(ours[i]) - ref[i]);
      norm += double(ref[i]) * ref[i];
    }
    EXPECT_LE(std::sqrt(diff), kGradientParity * std::sqrt(norm))
        << name << ": norm-wise relative error";
  };
  for (splat::ParamGroup group : splat::kAllParamGroups) {
    compare(splat::param_group(cpu.d_gaussians, group), splat::param_group(gpu.d_gaussians, group),
            label + " d_" + splat::param_group_name(group));
  }
  compare(cpu.d_means2d, gpu.d_means2d, label + " d_means2d");
  EXPECT_EQ(cpu.visible, gpu.visible) << label << " visible";
  const std::vector<float> pose_cpu(cpu.d_loss_d_pose.data(), cpu.d_loss_d_pose.data() + 6);
  const std::vector<float> pose_gpu(gpu.d_loss_d_pose.data(), gpu.d_loss_d_pose.data() + 6);
  expect_relative_parity(pose_cpu, pose_gpu, label + " d_loss_d_pose");
}

}  // namespace gslam::test
