// Backend parity checks: the Vulkan backend against the CPU reference, stage by stage.
#pragma once
#include <string>
#include <vector>

#include "splat/rasterizer.h"

namespace gslam::test {

// Images (RGB, alpha, depth): every pixel within this absolute bound (the target).
// Both backends use the same exp polynomial and cut-offs; what remains is float summation
// order and fused multiply-adds, ~1e-6 on these scenes.
inline constexpr float kImageParity = 1e-4f;
// Gradients and Jacobians: relative error bound on each element, measured against
// |reference| + kRelativeFloor x (largest |reference| of its group), so near-cancelling
// elements (a sum of terms of both signs, added in another order on the GPU) are judged
// against the group's scale rather than their own tiny value.
inline constexpr float kGradientParity = 1e-3f;
inline constexpr float kRelativeFloor = 1e-2f;

// Checks rendered images; with `stages`, also the per-Gaussian projection outputs, radii, each
// tile's sorted splat list and the last contributor of every pixel (exact where integral).
void expect_forward_parity(const splat::ForwardResult& cpu, const splat::ForwardResult& gpu,
                           bool stages, const std::string& label);

// Every element of `ours` against `ref` with the relative rule above; lists each mismatch.
void expect_relative_parity(const std::vector<float>& ref, const std::vector<float>& ours,
                            const std::string& label);

// How backward results are compared: element by element (the rule above), or per group by
// the norm-wise relative error ||gpu - cpu|| / ||cpu|| <= kGradientParity. Real maps with
// per-pixel noise as the upstream gradient make elements that are sums of thousands of
// cancelling terms; there the CPU float reference itself misses the element-wise rule against
// the double reference (measured up to 4.4x the bound on the donut), so only the norm-wise
// error is meaningful.
enum class GradientRule { kElementwise, kNormwise };

void expect_backward_parity(const splat::BackwardResult& cpu, const splat::BackwardResult& gpu,
                            const std::string& label,
                            GradientRule rule = GradientRule::kElementwise);

}  // namespace gslam::test
