#pragma once
#include <map>
#include <string>

#include "splat/rasterizer.h"
#include "splat/thread_pool.h"

namespace splat {

// Wall time per pipeline stage in milliseconds, summed over calls (for profiling).
using StageTimes = std::map<std::string, double>;

// The CPU reference pipeline, for float (what make_cpu_rasterizer runs) and double (gradient
// checks against finite differences). Same contract as Rasterizer::forward/backward. Where
// `times` is given, each stage's wall time is added to it.
template <typename Scalar>
ForwardResultT<Scalar> reference_forward(const GaussiansViewT<Scalar>& gaussians,
                                         const Camera& camera, const RenderSettings& settings,
                                         ThreadPool& pool, StageTimes* times = nullptr);

// Memory reference_backward can reuse across calls (per-intersection gradients).
template <typename Scalar>
struct BackwardScratch {
  std::vector<Scalar> intersections;
};

template <typename Scalar>
BackwardResultT<Scalar> reference_backward(const ForwardResultT<Scalar>& forward,
                                           const ImageGradsT<Scalar>& d_image, ThreadPool& pool,
                                           BackwardScratch<Scalar>* scratch = nullptr,
                                           StageTimes* times = nullptr);

// The readable oracle of compositing, for tests: plain loops per pixel and per splat, reading
// like shaders/rasterize_*.comp, with the per-pixel maths every backend shares.
// scalar_composite recomputes a forward result's images (rgb, alpha, depth, depth_normalized,
// last_contributor, final_transmittance) from its intermediates (means2d .. sorted_ids, as a
// forward with RenderSettings::intermediates leaves them, from either backend).
template <typename Scalar>
void scalar_composite(ForwardResultT<Scalar>& frame);
// Gradients through the oracle's compositing, then the CPU projection's backward.
template <typename Scalar>
BackwardResultT<Scalar> scalar_reference_backward(const ForwardResultT<Scalar>& forward,
                                                  const ImageGradsT<Scalar>& d_image, ThreadPool& pool);

// Jacobian of every output pixel with respect to the camera pose (left perturbation
// T_cam_world <- exp([v, w]) T_cam_world), by forward-mode differentiation, into `jacobian`
// (resized, every element overwritten): [H, W, 5, 6] for (r, g, b, depth, alpha) x (v, w).
template <typename Scalar>
void reference_pose_jacobian(const ForwardResultT<Scalar>& forward, ThreadPool& pool,
                             std::vector<Scalar>& jacobian, StageTimes* times = nullptr);

}  // namespace splat
