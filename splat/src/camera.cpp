#include "splat/camera.h"

#include <cmath>
#include <sstream>
#include <string>

#include "splat/error.h"

namespace splat {

void Camera::validate(std::string_view where) const {
  auto fail = [&](const std::string& what) { throw Error(std::string(where) + ": " + what); };
  for (auto [name, value] : {std::pair{"fx", fx}, {"fy", fy}}) {
    if (!std::isfinite(value) || value <= 0) {
      fail(std::string("camera ") + name + " is " + std::to_string(value) +
           ", expected a positive finite focal length");
    }
  }
  if (!std::isfinite(cx) || !std::isfinite(cy)) fail("camera principal point is not finite");
  constexpr int kMaxSide = 16384;  // far beyond any sensor; guards against garbage sizes
  if (width < 1 || height < 1 || width > kMaxSide || height > kMaxSide) {
    fail("image size is " + std::to_string(width) + "x" + std::to_string(height) +
         ", expected 1..16384 on each side");
  }
  if (!(near > 0) || !(far > near)) {
    fail("near/far are " + std::to_string(near) + "/" + std::to_string(far) +
         ", expected 0 < near < far");
  }
  const Eigen::Matrix4d m = T_cam_world.matrix();
  if (!m.allFinite()) fail("camera pose is not finite");
  const Eigen::Matrix3d r = T_cam_world.linear();
  constexpr double kRotationTolerance = 1e-6;  // accepts poses parsed from 7-digit text files
  if ((r * r.transpose() - Eigen::Matrix3d::Identity()).norm() > kRotationTolerance ||
      r.determinant() < 0) {
    fail("camera pose rotation is not orthonormal");
  }
}

}  // namespace splat
