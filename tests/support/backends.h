// The rasterizer backends contract and parity tests run on.
#pragma once
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "splat/rasterizer.h"

namespace gslam::test {

// "cpu", and "vulkan" when the build has the Vulkan backend.
std::vector<std::string> backend_names();

// One rasterizer per backend for the whole test process (creating Vulkan pipelines is slow),
// or null with the reason when the backend cannot run here. Names: "cpu", "vulkan" (float
// atomics where the device has them) and "vulkan_portable" (the portable reduction, and every
// transfer through staging copies as on a discrete GPU, even where memory could be mapped).
splat::Rasterizer* shared_backend(const std::string& name, std::string& why_not);

// Whether a missing Vulkan device fails tests instead of skipping them (GSLAM_REQUIRE_GPU_TESTS,
// at build time, on in CI, or in the environment: the Vulkan tests cannot silently vanish).
bool gpu_tests_required();

}  // namespace gslam::test

// Declares `var` as the named backend's rasterizer; skips the test, or fails it when GPU tests
// are required, if that backend cannot run here.
#define GSLAM_REQUIRE_BACKEND(var, name)                                             \
  std::string var##_why_not;                                                         \
  splat::Rasterizer* var##_ptr = ::gslam::test::shared_backend(name, var##_why_not); \
  if (!var##_ptr) {                                                                  \
    if (::gslam::test::gpu_tests_required()) {                                       \
      FAIL() << "backend " << (name) << " unavailable: " << var##_why_not;           \
    }                                                                                \
    GTEST_SKIP() << "backend " << (name) << " unavailable: " << var##_why_not;       \
  }                                                                                  \
  splat::Rasterizer& var = *var##_ptr
