// The stages of the CPU reference, in pipeline order. Each reads and writes the ForwardResult
// that carries the frame, so every intermediate buffer stays inspectable.
#pragma once
#include <vector>

#include "splat/rasterizer.h"
#include "splat/thread_pool.h"
#include "shader_io.h"

namespace splat::cpu {

// dL/d(per-Gaussian screen quantities): what compositing's backward hands to projection's.
template <typename T>
struct ScreenGrads {
  explicit ScreenGrads(std::size_t n = 0)
      : means2d(n * 2, 0), conics(n * 3, 0), opacities(n, 0), colors(n * 3, 0), depths(n, 0) {}
  std::vector<T> means2d;    // [N, 2]
  std::vector<T> conics;     // [N, 3]
  std::vector<T> opacities;  // [N]
  std::vector<T> colors;     // [N, 3]
  std::vector<T> depths;     // [N]
};

// Projection: 3D Gaussians to 2D means, conics, depths, radii, colours and opacities.
template <typename T>
void project_forward(ForwardResultT<T>& frame, ThreadPool& pool);

// Tiling: lists every (tile, splat) pair and sorts each tile's list front to back.
template <typename T>
void bin_and_sort(ForwardResultT<T>& frame, ThreadPool& pool);

// Compositing: blends each tile's sorted splats into the output images.
template <typename T>
void composite_forward(ForwardResultT<T>& frame, ThreadPool& pool);

// Backward of compositing: per-Gaussian gradients of the screen quantities. `scratch` holds
// per-intersection gradients; reusing it across calls avoids reallocating it.
template <typename T>
ScreenGrads<T> composite_backward(const ForwardResultT<T>& frame, const ImageGradsT<T>& d_image,
                                  ThreadPool& pool, std::vector<T>& scratch);

// The readable oracle of the two passes above (composite_scalar.cpp): one pixel and one splat
// at a time, as the shaders read. Tests compare the vectorized and Vulkan compositing with it.
template <typename T>
void scalar_composite_forward(ForwardResultT<T>& frame);
template <typename T>
ScreenGrads<T> scalar_composite_backward(const ForwardResultT<T>& frame, const ImageGradsT<T>& d_image);

// Backward of projection: gradients of the Gaussian parameters and of the camera pose.
template <typename T>
void project_backward(const ForwardResultT<T>& frame, const ScreenGrads<T>& screen,
                      BackwardResultT<T>& out, ThreadPool& pool);

}  // namespace splat::cpu

namespace splat::cpu {

// Forward-mode derivatives of the screen quantities with respect to the pose (left perturbation
// of T_cam_world), per Gaussian: [N, kScreenValues, 6] in the order mean x, mean y, conic a,
// b, c, depth, colour r, g, b. Zero for culled Gaussians.
inline constexpr int kScreenValues = static_cast<int>(io::kScreenValues);
template <typename T>
std::vector<T> project_pose_jvp(const ForwardResultT<T>& frame, ThreadPool& pool);

// Per-pixel Jacobian of (r, g, b, depth, alpha) with respect to the pose: [H, W, 5, 6], into
// `out` (resized; every element written).
template <typename T>
void composite_pose_jvp(const ForwardResultT<T>& frame, const std::vector<T>& screen_jvp,
                        ThreadPool& pool, std::vector<T>& out);

}  // namespace splat::cpu
