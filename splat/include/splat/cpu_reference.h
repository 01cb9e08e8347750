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

// Jacobian of every output pixel with respect to the camera pose (left perturbation
// T_cam_world <- exp([v, w]) T_cam_world), by forward-mode differentiation, into `jacobian`
// (resized, every element overwritten): [H, W, 5, 6] for (r, g, b, depth, alpha) x (v, w).
template <typename Scalar>
void reference_pose_jacobian(const ForwardResultT<Scalar>& forward, ThreadPool& pool,
                             std::vector<Scalar>& jacobian, StageTimes* times = nullptr);

}  // namespace splat
