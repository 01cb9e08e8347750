#include <gtest/gtest.h>

#include "splat/se3.h"

namespace {

TEST(Se3, LogInvertsExpAndSmallAnglesStayAccurate) {
  const splat::Vector6d twists[] = {
      (splat::Vector6d() << 0.3, -0.2, 1.1, 0.4, -0.7, 0.25).finished(),
      (splat::Vector6d() << 1e-3, 2e-3, -1e-3, 1e-8, -2e-8, 3e-8).finished(),
      (splat::Vector6d() << 0, 0, 0, 0, 0, 0).finished(),
  };
  for (const auto& xi : twists) {
    const splat::Vector6d back = splat::se3_log(splat::se3_exp(xi));
    EXPECT_LT((back - xi).norm(), 1e-9) << xi.transpose();
  }
  // exp of a pure rotation about z by 90 degrees.
  const Eigen::Isometry3d r = splat::se3_exp((splat::Vector6d() << 0, 0, 0, 0, 0, M_PI / 2).finished());
  EXPECT_TRUE((r * Eigen::Vector3d::UnitX()).isApprox(Eigen::Vector3d::UnitY(), 1e-12));
  Eigen::Isometry3d scaled = r;
  scaled.linear() *= 1.0 + 1e-5;  // what long chains of composed updates drift into
  const Eigen::Isometry3d drifted = splat::orthonormalized(scaled);
  EXPECT_LT((drifted.linear() * drifted.linear().transpose() - Eigen::Matrix3d::Identity()).norm(), 1e-12);
}

}  // namespace
