#include "splat/se3.h"

#include <cmath>

namespace splat {
namespace {

Eigen::Matrix3d hat(const Eigen::Vector3d& w) {
  Eigen::Matrix3d m;
  m << 0, -w.z(), w.y(), w.z(), 0, -w.x(), -w.y(), w.x(), 0;
  return m;
}

// V = I + (1 - cos t)/t^2 W + (t - sin t)/t^3 W^2, the left Jacobian of SO(3).
Eigen::Matrix3d left_jacobian(const Eigen::Vector3d& w) {
  const double theta = w.norm();
  const Eigen::Matrix3d wx = hat(w);
  if (theta < 1e-6) return Eigen::Matrix3d::Identity() + 0.5 * wx + wx * wx / 6.0;  // Taylor
  const double t2 = theta * theta;
  return Eigen::Matrix3d::Identity() + (1 - std::cos(theta)) / t2 * wx +
         (theta - std::sin(theta)) / (t2 * theta) * wx * wx;
}

}  // namespace

Eigen::Isometry3d se3_exp(const Vector6d& delta) {
  const Eigen::Vector3d v = delta.head<3>(), w = delta.tail<3>();
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  const double theta = w.norm();
  t.linear() = theta > 0 ? Eigen::AngleAxisd(theta, w / theta).toRotationMatrix()
                         : Eigen::Matrix3d::Identity();
  t.translation() = left_jacobian(w) * v;
  return t;
}

Eigen::Isometry3d orthonormalized(const Eigen::Isometry3d& transform) {
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = Eigen::Quaterniond(transform.linear()).normalized().toRotationMatrix();
  out.translation() = transform.translation();
  return out;
}

Vector6d se3_log(const Eigen::Isometry3d& transform) {
  const Eigen::AngleAxisd aa(transform.linear());
  const Eigen::Vector3d w = aa.axis() * aa.angle();
  Vector6d out;
  out.head<3>() = left_jacobian(w).inverse() * transform.translation();
  out.tail<3>() = w;
  return out;
}

}  // namespace splat
