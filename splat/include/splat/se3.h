#pragma once
#include <Eigen/Geometry>

namespace splat {

using Vector6d = Eigen::Matrix<double, 6, 1>;

// Exponential map of se(3), delta = [v, omega] (translation part first), to a rigid transform.
Eigen::Isometry3d se3_exp(const Vector6d& delta);

// Inverse of se3_exp: the twist [v, omega] of a rigid transform (rotation angle below pi).
Vector6d se3_log(const Eigen::Isometry3d& transform);

// The nearest rigid transform: the rotation re-orthonormalized (through a unit quaternion).
// Long chains of composed updates otherwise drift away from SO(3).
Eigen::Isometry3d orthonormalized(const Eigen::Isometry3d& transform);

}  // namespace splat
