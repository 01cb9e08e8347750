#pragma once
#include "splat/rasterizer.h"
#include "splat/thread_pool.h"

namespace splat {

// The CPU reference pipeline, for float (what make_cpu_rasterizer runs) and double (gradient
// checks against finite differences). Same contract as Rasterizer::forward/backward.
template <typename Scalar>
ForwardResultT<Scalar> reference_forward(const GaussiansViewT<Scalar>& gaussians,
                                         const Camera& camera, const RenderSettings& settings,
                                         ThreadPool& pool);

template <typename Scalar>
BackwardResultT<Scalar> reference_backward(const ForwardResultT<Scalar>& forward,
                                           const ImageGradsT<Scalar>& d_image, ThreadPool& pool);

}  // namespace splat
