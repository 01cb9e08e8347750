#include "support/parity.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "shader_io.h"

namespace gslam::test {
namespace {

void expect_images_close(const std::vector<float>& ref, const std::vector<float>& ours, int width,
                         int channels, const std::vector<bool>& skip, const char* name,
                         const std::string& label) {
  ASSERT_EQ(ref.size(), ours.size()) << label << " " << name;
  int reported = 0;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    if (std::abs(ref[i] - ours[i]) <= kImageParity) continue;
    const std::size_t pixel = i / static_cast<std::size_t>(channels);
    if (!skip.empty() && skip[pixel]) continue;
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

CutoffPixels near_cutoffs(const splat::ForwardResult& f) {
  CutoffPixels out;
  out.pixel.assign(std::size_t(f.width) * f.height, false);
  if (f.sorted_ids.empty()) return out;
  const auto near = [](double value, double cut) {
    return std::abs(value - cut) <= kCutoffMargin * cut;
  };
  const int tile = int(splat::io::kTileSize);
  for (int py = 0; py < f.height; ++py) {
    for (int px = 0; px < f.width; ++px) {
      const std::size_t t = std::size_t(py / tile) * f.tiles_x + px / tile;
      double transmittance = 1;
      bool ambiguous = false;
      for (uint32_t k = f.tile_ranges[2 * t]; k < f.tile_ranges[2 * t + 1]; ++k) {
        const uint32_t id = f.sorted_ids[k];
        const double dx = f.means2d[2 * id] - (px + 0.5), dy = f.means2d[2 * id + 1] - (py + 0.5);
        const double sigma = 0.5 * (f.conics[3 * id] * dx * dx + f.conics[3 * id + 2] * dy * dy) +
                             f.conics[3 * id + 1] * dx * dy;
        if (sigma < 0) continue;
        const double raw = f.opacities[id] * std::exp(-sigma);
        ambiguous |= near(raw, splat::io::kAlphaMin) || near(raw, splat::io::kAlphaMax);
        if (raw < splat::io::kAlphaMin) continue;
        const double next = transmittance * (1 - std::min(raw, double(splat::io::kAlphaMax)));
        ambiguous |= near(next, splat::io::kTransmittanceMin);
        if (ambiguous || next <= splat::io::kTransmittanceMin) break;
        transmittance = next;
      }
      if (!ambiguous) continue;
      out.pixel[std::size_t(py) * f.width + px] = true;
      ++out.pixels;
    }
  }
  return out;
}

void expect_relative_parity(const std::vector<float>& ref, const std::vector<float>& ours,
                            const std::string& label, const std::vector<bool>& skip,
                            std::size_t per_item) {
  ASSERT_EQ(ref.size(), ours.size()) << label;
  const float floor = kRelativeFloor * largest_abs(ref);
  int reported = 0;
  for (std::size_t i = 0; i < ref.size(); ++i) {
    if (!skip.empty() && skip[i / per_item]) continue;
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
  const CutoffPixels cut = near_cutoffs(cpu);
  EXPECT_LE(cut.pixels * 100, cut.pixel.size())
      << label << ": " << cut.pixels << " pixels near a compositing cut-off";
  expect_images_close(cpu.rgb, gpu.rgb, cpu.width, 3, cut.pixel, "rgb", label);
  expect_images_close(cpu.alpha, gpu.alpha, cpu.width, 1, cut.pixel, "alpha", label);
  expect_images_close(cpu.depth, gpu.depth, cpu.width, 1, cut.pixel, "depth", label);
  EXPECT_EQ(cpu.stats.visible, gpu.stats.visible) << label;
  if (!stages) return;
  expect_relative_parity(cpu.means2d, gpu.means2d, label + " means2d");
  expect_relative_parity(cpu.conics, gpu.conics, label + " conics");
  expect_relative_parity(cpu.depths, gpu.depths, label + " depths");
  expect_relative_parity(cpu.colors, gpu.colors, label + " colors");
  EXPECT_EQ(cpu.radii, gpu.radii) << label << " radii";
  EXPECT_EQ(cpu.stats.intersections, gpu.stats.intersections) << label;
  ASSERT_EQ(cpu.last_contributor.size(), gpu.last_contributor.size()) << label;
  for (std::size_t p = 0; p < cpu.last_contributor.size(); ++p) {
    if (cut.pixel[p]) continue;
    ASSERT_EQ(cpu.last_contributor[p], gpu.last_contributor[p]) << label << " last contributor of "
                                                                << "pixel " << p;
  }
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

splat::ImageGrads zero_near_cutoffs(const splat::ForwardResult& cpu, splat::ImageGrads d) {
  const CutoffPixels cut = near_cutoffs(cpu);
  for (std::size_t p = 0; p < cut.pixel.size(); ++p) {
    if (!cut.pixel[p]) continue;
    for (std::vector<float>* image : {&d.rgb, &d.alpha, &d.depth}) {
      const std::size_t channels = image->size() / cut.pixel.size();
      std::fill_n(image->begin() + std::ptrdiff_t(p * channels), channels, 0.f);
    }
  }
  return d;
}

void expect_pose_jacobian_parity(const splat::ForwardResult& cpu_forward,
                                 const std::vector<float>& ref, const std::vector<float>& ours,
                                 const std::string& label) {
  expect_relative_parity(ref, ours, label, near_cutoffs(cpu_forward).pixel, 5 * 6);
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
  const std::vector<float> pose_cpu(cpu.d_loss_d_pose.data(), cpu.d_loss_d_pose.data() + 6);
  const std::vector<float> pose_gpu(gpu.d_loss_d_pose.data(), gpu.d_loss_d_pose.data() + 6);
  expect_relative_parity(pose_cpu, pose_gpu, label + " d_loss_d_pose");
}

}  // namespace gslam::test
