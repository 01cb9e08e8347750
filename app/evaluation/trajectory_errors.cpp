#include "evaluation/trajectory_errors.h"

#include <cmath>

#include <Eigen/Geometry>

#include "datasets/dataset.h"
#include "splat/error.h"

namespace app {

TrajectoryErrors evaluate_trajectory(const std::vector<StampedPose>& estimate,
                                     const std::vector<StampedPose>& truth, bool sim3,
                                     double rpe_delta) {
  std::vector<double> te, tt;
  for (const auto& p : estimate) te.push_back(p.timestamp);
  for (const auto& p : truth) tt.push_back(p.timestamp);
  const auto pairs = associate(te, tt);
  if (pairs.size() < 3) {
    throw splat::Error("evaluate: only " + std::to_string(pairs.size()) + " estimated poses have ground truth within 0.02 s; need 3");
  }
  TrajectoryErrors out;
  out.matched = pairs.size();
  Eigen::Matrix3Xd src(3, pairs.size()), dst(3, pairs.size());
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    src.col(static_cast<long>(k)) = estimate[pairs[k].first].T_world_cam.translation();
    dst.col(static_cast<long>(k)) = truth[pairs[k].second].T_world_cam.translation();
  }
  // Horn/Umeyama: the similarity (or rigid) transform taking estimate positions onto the truth.
  const Eigen::Matrix4d a = Eigen::umeyama(src, dst, sim3);
  out.scale = sim3 ? std::cbrt(a.topLeftCorner<3, 3>().determinant()) : 1.0;
  double sum = 0;
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    const Eigen::Vector3d p = a.topLeftCorner<3, 3>() * src.col(static_cast<long>(k)) + a.topRightCorner<3, 1>();
    const double e = (p - dst.col(static_cast<long>(k))).norm();
    out.times.push_back(te[pairs[k].first]);
    out.ate_errors.push_back(e);
    out.aligned_estimate.push_back(p);
    out.truth.push_back(dst.col(static_cast<long>(k)));
    sum += e * e;
    out.ate_mean += e / static_cast<double>(pairs.size());
    out.ate_max = std::max(out.ate_max, e);
  }
  out.ate_rmse = std::sqrt(sum / static_cast<double>(pairs.size()));

  // RPE: relative motion over rpe_delta seconds, estimate against truth (scale applied).
  double sum_t = 0, sum_r = 0;
  for (std::size_t i = 0; i < pairs.size(); ++i) {
    std::size_t j = i;
    while (j + 1 < pairs.size() && te[pairs[j].first] < te[pairs[i].first] + rpe_delta) ++j;
    if (te[pairs[j].first] - te[pairs[i].first] < rpe_delta * 0.9) break;  // no partner far enough
    const Eigen::Isometry3d gt = truth[pairs[i].second].T_world_cam.inverse() * truth[pairs[j].second].T_world_cam;
    Eigen::Isometry3d est = estimate[pairs[i].first].T_world_cam.inverse() * estimate[pairs[j].first].T_world_cam;
    est.translation() *= out.scale;
    const Eigen::Isometry3d error = gt.inverse() * est;
    sum_t += error.translation().squaredNorm();
    const double angle = Eigen::AngleAxisd(error.linear()).angle() * 180 / M_PI;
    sum_r += angle * angle;
    ++out.rpe_pairs;
  }
  if (out.rpe_pairs > 0) {
    out.rpe_translation_rmse = std::sqrt(sum_t / static_cast<double>(out.rpe_pairs));
    out.rpe_rotation_rmse_deg = std::sqrt(sum_r / static_cast<double>(out.rpe_pairs));
  }
  return out;
}

}  // namespace app
