// What both rasterizer backends share outside the per-Gaussian maths.
#include <string>

#include "splat/error.h"
#include "splat/rasterizer.h"
#include "splat/resident_map.h"

namespace splat {

std::unique_ptr<ResidentMap> Rasterizer::make_resident_map(int) { return nullptr; }

template <typename Scalar>
void validate_image_grads(const ForwardResultT<Scalar>& forward,
                          const ImageGradsT<Scalar>& d_image) {
  const std::size_t pixels = static_cast<std::size_t>(forward.width) * forward.height;
  auto check = [&](const std::vector<Scalar>& v, std::size_t channels, const char* name) {
    if (!v.empty() && v.size() != pixels * channels) {
      throw Error(std::string("rasterize backward: d_") + name + " has " +
                  std::to_string(v.size()) + " values, expected " +
                  std::to_string(pixels * channels) + " for " + std::to_string(forward.width) +
                  "x" + std::to_string(forward.height) + "x" + std::to_string(channels));
    }
  };
  check(d_image.rgb, 3, "rgb");
  check(d_image.alpha, 1, "alpha");
  check(d_image.depth, 1, "depth");
}

template void validate_image_grads(const ForwardResultT<float>&, const ImageGradsT<float>&);
template void validate_image_grads(const ForwardResultT<double>&, const ImageGradsT<double>&);

PoseGradient pose_gradient_from(const Eigen::Matrix3d& d_w, const Eigen::Vector3d& d_t,
                                const Eigen::Matrix3d& w, const Eigen::Vector3d& t) {
  // Left perturbation T <- exp([v, w]) T: dW = [w]x W, dt = v + [w]x t. With A = dL/dW W^T +
  // dL/dt t^T, dL/dw = (A32 - A23, A13 - A31, A21 - A12) and dL/dv = dL/dt.
  const Eigen::Matrix3d a = d_w * w.transpose() + d_t * t.transpose();
  PoseGradient g;
  g << d_t, a(2, 1) - a(1, 2), a(0, 2) - a(2, 0), a(1, 0) - a(0, 1);
  return g;
}

}  // namespace splat
