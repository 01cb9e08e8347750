#pragma once
#include <filesystem>
#include <map>
#include <string>

#include "splat/camera.h"
#include "splat/gaussians.h"
#include "support/safetensors.h"

namespace gslam::test {

// Brush's comparison criterion for gsplat's golden vectors: |ours - ref| <= atol + rtol |ref|.
inline constexpr float kGoldenAtol = 1e-5f;
inline constexpr float kGoldenRtol = 1e-2f;

// One of gsplat's golden cases with the camera its SOURCE.md describes.
struct GoldenCase {
  std::map<std::string, Tensor> tensors;
  splat::Gaussians gaussians;
  splat::Camera camera;
  const Tensor& tensor(const std::string& name) const { return tensors.at(name); }
};

GoldenCase load_golden_case(const std::filesystem::path& path);

}  // namespace gslam::test
