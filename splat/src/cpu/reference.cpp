#include <chrono>
#include <string>

#include "cpu/stages.h"
#include "splat/cpu_reference.h"
#include "splat/error.h"

namespace splat {
namespace {

// Runs one stage, adding its wall time to `times` under `name` where times are kept.
template <typename Fn>
auto timed(StageTimes* times, const char* name, Fn&& stage) {
  const auto start = std::chrono::steady_clock::now();
  struct AddOnExit {
    StageTimes* times;
    const char* name;
    std::chrono::steady_clock::time_point start;
    ~AddOnExit() {
      if (times) {
        (*times)[name] += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      }
    }
  } add{times, name, start};
  return stage();
}

}  // namespace

template <typename Scalar>
ForwardResultT<Scalar> reference_forward(const GaussiansViewT<Scalar>& gaussians,
                                         const Camera& camera, const RenderSettings& settings,
                                         ThreadPool& pool, StageTimes* times) {
  validate(gaussians, "rasterize", &pool);
  camera.validate("rasterize");
  ForwardResultT<Scalar> frame;
  frame.gaussians = gaussians;
  frame.camera = camera;
  frame.settings = settings;
  timed(times, "project", [&] { cpu::project_forward(frame, pool); });
  timed(times, "sort_and_bin", [&] { cpu::bin_and_sort(frame, pool); });
  timed(times, "composite", [&] { cpu::composite_forward(frame, pool); });
  return frame;
}

template <typename Scalar>
BackwardResultT<Scalar> reference_backward(const ForwardResultT<Scalar>& forward,
                                           const ImageGradsT<Scalar>& d_image, ThreadPool& pool,
                                           BackwardScratch<Scalar>* scratch, StageTimes* times) {
  validate_image_grads(forward, d_image);
  BackwardResultT<Scalar> out;
  BackwardScratch<Scalar> local;
  BackwardScratch<Scalar>& memory = scratch ? *scratch : local;
  const cpu::ScreenGrads<Scalar> screen = timed(times, "composite_backward", [&] {
    return cpu::composite_backward(forward, d_image, pool, memory.intersections);
  });
  timed(times, "project_backward", [&] { cpu::project_backward(forward, screen, out, pool); });
  return out;
}

template <typename Scalar>
void reference_pose_jacobian(const ForwardResultT<Scalar>& forward, ThreadPool& pool,
                             std::vector<Scalar>& jacobian, StageTimes* times) {
  const std::vector<Scalar> screen =
      timed(times, "project_pose_jvp", [&] { return cpu::project_pose_jvp(forward, pool); });
  timed(times, "composite_pose_jvp", [&] { cpu::composite_pose_jvp(forward, screen, pool, jacobian); });
}

template <typename Scalar>
void scalar_composite(ForwardResultT<Scalar>& frame) {
  const std::size_t n = frame.gaussians.size();
  const std::size_t tiles = static_cast<std::size_t>(frame.tiles_x) * frame.tiles_y;
  if (frame.means2d.size() != n * 2 || frame.conics.size() != n * 3 || frame.opacities.size() != n ||
      frame.colors.size() != n * 3 || frame.depths.size() != n || frame.tile_ranges.size() != tiles * 2 ||
      tiles == 0) {
    throw Error("scalar_composite: the forward result has no intermediates for its " + std::to_string(n) +
                " Gaussians (render with RenderSettings::intermediates)");
  }
  cpu::scalar_composite_forward(frame);
}

template <typename Scalar>
BackwardResultT<Scalar> scalar_reference_backward(const ForwardResultT<Scalar>& forward,
                                                  const ImageGradsT<Scalar>& d_image, ThreadPool& pool) {
  validate_image_grads(forward, d_image);
  BackwardResultT<Scalar> out;
  cpu::project_backward(forward, cpu::scalar_composite_backward(forward, d_image), out, pool);
  return out;
}

template void scalar_composite(ForwardResultT<float>&);
template void scalar_composite(ForwardResultT<double>&);
template BackwardResultT<float> scalar_reference_backward(const ForwardResultT<float>&, const ImageGradsT<float>&,
                                                          ThreadPool&);
template BackwardResultT<double> scalar_reference_backward(const ForwardResultT<double>&,
                                                           const ImageGradsT<double>&, ThreadPool&);
template void reference_pose_jacobian(const ForwardResultT<float>&, ThreadPool&, std::vector<float>&,
                                      StageTimes*);
template void reference_pose_jacobian(const ForwardResultT<double>&, ThreadPool&, std::vector<double>&,
                                      StageTimes*);
template ForwardResultT<float> reference_forward(const GaussiansViewT<float>&, const Camera&,
                                                 const RenderSettings&, ThreadPool&, StageTimes*);
template ForwardResultT<double> reference_forward(const GaussiansViewT<double>&, const Camera&,
                                                  const RenderSettings&, ThreadPool&, StageTimes*);
template BackwardResultT<float> reference_backward(const ForwardResultT<float>&,
                                                   const ImageGradsT<float>&, ThreadPool&,
                                                   BackwardScratch<float>*, StageTimes*);
template BackwardResultT<double> reference_backward(const ForwardResultT<double>&,
                                                    const ImageGradsT<double>&, ThreadPool&,
                                                    BackwardScratch<double>*, StageTimes*);

}  // namespace splat
