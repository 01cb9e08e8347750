#include <string>

#include "cpu/stages.h"
#include "splat/cpu_reference.h"
#include "splat/error.h"

namespace splat {

template <typename Scalar>
ForwardResultT<Scalar> reference_forward(const GaussiansViewT<Scalar>& gaussians,
                                         const Camera& camera, const RenderSettings& settings,
                                         ThreadPool& pool) {
  validate(gaussians, "rasterize");
  camera.validate("rasterize");
  ForwardResultT<Scalar> frame;
  frame.gaussians = gaussians;
  frame.camera = camera;
  frame.settings = settings;
  cpu::project_forward(frame, pool);
  cpu::bin_and_sort(frame, pool);
  cpu::composite_forward(frame, pool);
  return frame;
}

template <typename Scalar>
BackwardResultT<Scalar> reference_backward(const ForwardResultT<Scalar>& forward,
                                           const ImageGradsT<Scalar>& d_image, ThreadPool& pool,
                                           BackwardScratch<Scalar>* scratch) {
  validate_image_grads(forward, d_image);
  BackwardResultT<Scalar> out;
  BackwardScratch<Scalar> local;
  BackwardScratch<Scalar>& memory = scratch ? *scratch : local;
  const cpu::ScreenGrads<Scalar> screen =
      cpu::composite_backward(forward, d_image, pool, memory.intersections);
  cpu::project_backward(forward, screen, out, pool);
  return out;
}

template <typename Scalar>
std::vector<Scalar> reference_pose_jacobian(const ForwardResultT<Scalar>& forward, ThreadPool& pool) {
  return cpu::composite_pose_jvp(forward, cpu::project_pose_jvp(forward, pool), pool);
}

template std::vector<float> reference_pose_jacobian(const ForwardResultT<float>&, ThreadPool&);
template std::vector<double> reference_pose_jacobian(const ForwardResultT<double>&, ThreadPool&);
template ForwardResultT<float> reference_forward(const GaussiansViewT<float>&, const Camera&,
                                                 const RenderSettings&, ThreadPool&);
template ForwardResultT<double> reference_forward(const GaussiansViewT<double>&, const Camera&,
                                                  const RenderSettings&, ThreadPool&);
template BackwardResultT<float> reference_backward(const ForwardResultT<float>&,
                                                   const ImageGradsT<float>&, ThreadPool&,
                                                   BackwardScratch<float>*);
template BackwardResultT<double> reference_backward(const ForwardResultT<double>&,
                                                    const ImageGradsT<double>&, ThreadPool&,
                                                    BackwardScratch<double>*);

}  // namespace splat
