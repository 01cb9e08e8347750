// Backend parity checks: the Vulkan backend against the CPU reference, stage by stage.
#pragma once
#include <string>
#include <vector>

#include "splat/rasterizer.h"

namespace gslam::test {

// Images (RGB, alpha, depth): every pixel within this absolute bound (the target).
// Compositing is bit-identical given the same splats (composite_oracle_test.cpp); what remains
// is projection's division and square root on the GPU, ~1e-6 on these scenes.
inline constexpr float kImageParity = 1e-4f;
// Gradients and Jacobians: relative error bound on each element, measured against
// |reference| + kRelativeFloor x (largest |reference| of its group), so near-cancelling
// elements (a sum of terms of both signs, added in another order on the GPU) are judged
// against the group's scale rather than their own tiny value.
inline constexpr float kGradientParity = 1e-3f;
inline constexpr float kRelativeFloor = 1e-2f;

// Compositing has cut-offs (skip alpha < 1/255, cap alpha at 0.999, stop once transmittance
// would fall to 1e-4) where an ulp decides whether a splat counts at a pixel. Backends that
// round differently (a GPU's own division, sqrt and fused multiply-adds: NVIDIA's do, lavapipe's
// happen not to here) may then legitimately disagree there by a whole splat. These are the
// pixels where, in double from the CPU result's intermediates, some splat's alpha or the
// transmittance after it lies within a relative kCutoffMargin of a cut-off. Image checks set these pixels aside (asserting they stay under 1%), and
// backward checks take no upstream gradient from them (zero_near_cutoffs), so that every
// Gaussian's gradient is still compared.
inline constexpr double kCutoffMargin = 1e-4;
struct CutoffPixels {
  std::vector<bool> pixel;  // [H * W]
  std::size_t pixels = 0;   // how many are marked
};
// Needs the CPU result's intermediates (RenderSettings::intermediates); none are marked without.
CutoffPixels near_cutoffs(const splat::ForwardResult& cpu);
// `d` with every channel zeroed at the pixels near a cut-off of `cpu`.
splat::ImageGrads zero_near_cutoffs(const splat::ForwardResult& cpu, splat::ImageGrads d);

// Checks rendered images; with `stages`, also the per-Gaussian projection outputs, radii, each
// tile's sorted splat list and the last contributor of every pixel (exact where integral).
// Pixels near a cut-off (above) are not compared.
void expect_forward_parity(const splat::ForwardResult& cpu, const splat::ForwardResult& gpu,
                           bool stages, const std::string& label);

// Every element of `ours` against `ref` with the relative rule above; lists each mismatch.
// Elements are grouped `per_item` to an item (a Gaussian, a pixel); items marked in `skip`
// are not compared.
void expect_relative_parity(const std::vector<float>& ref, const std::vector<float>& ours,
                            const std::string& label, const std::vector<bool>& skip = {},
                            std::size_t per_item = 1);

// The [H, W, 5, 6] pose Jacobians, except at pixels near a cut-off of `cpu_forward`.
void expect_pose_jacobian_parity(const splat::ForwardResult& cpu_forward,
                                 const std::vector<float>& ref, const std::vector<float>& ours,
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
