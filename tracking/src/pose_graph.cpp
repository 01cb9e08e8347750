#include "tracking/pose_graph.h"

#include <cmath>
#include <memory>
#include <string>

#include <ceres/ceres.h>
#include <Eigen/Cholesky>

#include "splat/error.h"

namespace tracking {
namespace {

// Log of a rigid transform (unit quaternion q, translation t) as the twist [rho, omega] that
// splat::se3_exp maps back to it; templated for Ceres' automatic derivatives, with series
// where the closed forms divide by a vanishing angle.
template <typename T>
void se3_log(Eigen::Quaternion<T> q, const Eigen::Matrix<T, 3, 1>& t, T* out) {
  if (q.w() < T(0)) q.coeffs() = -q.coeffs();
  const Eigen::Matrix<T, 3, 1> v = q.vec();
  const T sin_half2 = v.squaredNorm();
  Eigen::Matrix<T, 3, 1> omega;
  if (sin_half2 < T(1e-16)) {
    omega = (T(2) / q.w()) * (T(1) - sin_half2 / (T(3) * q.w() * q.w())) * v;
  } else {
    const T sin_half = sqrt(sin_half2);
    omega = (T(2) * atan2(sin_half, q.w()) / sin_half) * v;
  }
  const T theta2 = omega.squaredNorm();
  T c;  // V^-1 = I - W / 2 + c W^2, W = [omega]x
  if (theta2 < T(1e-10)) {
    c = T(1.0 / 12.0) + theta2 / T(720.0);
  } else {
    const T theta = sqrt(theta2);
    c = (T(1) - theta * sin(theta) / (T(2) * (T(1) - cos(theta)))) / theta2;
  }
  const Eigen::Matrix<T, 3, 1> wt = omega.cross(t);
  const Eigen::Matrix<T, 3, 1> rho = t - T(0.5) * wt + c * omega.cross(wt);
  for (int k = 0; k < 3; ++k) out[k] = rho[k], out[k + 3] = omega[k];
}

struct EdgeResidual {
  Eigen::Quaterniond q_ij;
  Eigen::Vector3d t_ij;
  Eigen::Matrix<double, 6, 6> sqrt_information;  // L^T

  template <typename T>
  bool operator()(const T* qi_data, const T* ti_data, const T* qj_data, const T* tj_data, T* residual) const {
    const Eigen::Map<const Eigen::Quaternion<T>> qi(qi_data), qj(qj_data);
    const Eigen::Map<const Eigen::Matrix<T, 3, 1>> ti(ti_data), tj(tj_data);
    // E = Z^-1 T_i^-1 T_j.
    const Eigen::Quaternion<T> qi_inv = qi.conjugate();
    const Eigen::Quaternion<T> q_rel = qi_inv * qj;
    const Eigen::Matrix<T, 3, 1> t_rel = qi_inv * (tj - ti);
    const Eigen::Quaternion<T> z_inv = q_ij.conjugate().cast<T>();
    const Eigen::Quaternion<T> q_err = z_inv * q_rel;
    const Eigen::Matrix<T, 3, 1> t_err = z_inv * (t_rel - t_ij.cast<T>());
    T log[6];
    se3_log<T>(q_err.normalized(), t_err, log);
    const Eigen::Map<const Eigen::Matrix<T, 6, 1>> e(log);
    Eigen::Map<Eigen::Matrix<T, 6, 1>> out(residual);
    out = sqrt_information.cast<T>() * e;
    return true;
  }
};

struct Parameters {
  std::vector<Eigen::Quaterniond> q;
  std::vector<Eigen::Vector3d> t;
};

// Whitened squared residual of each edge at the parameters.
std::vector<double> edge_chi2(const Parameters& p, const std::vector<PoseGraphEdge>& edges,
                              const std::vector<EdgeResidual>& residuals) {
  std::vector<double> chi2(edges.size());
  for (std::size_t e = 0; e < edges.size(); ++e) {
    const PoseGraphEdge& edge = edges[e];
    double r[6];
    residuals[e](p.q[edge.i].coeffs().data(), p.t[edge.i].data(), p.q[edge.j].coeffs().data(), p.t[edge.j].data(), r);
    chi2[e] = 0;
    for (double v : r) chi2[e] += v * v;
  }
  return chi2;
}

double total(const std::vector<double>& chi2, const std::vector<bool>& use) {
  double sum = 0;
  for (std::size_t e = 0; e < chi2.size(); ++e) sum += use[e] ? chi2[e] : 0;
  return sum;
}


// Solves the graph over the edges in `use` from `start`, the poses in `fixed` constant;
// `scale` divides every information (the variance factor). Returns the iterations taken.
int solve(const Parameters& start, Parameters& p, const std::vector<PoseGraphEdge>& edges,
          std::vector<EdgeResidual> residuals, const std::vector<bool>& use, const std::vector<std::size_t>& fixed,
          const PoseGraphConfig& config) {
  p = start;
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  ceres::EigenQuaternionManifold quaternion;
  for (std::size_t e = 0; e < edges.size(); ++e) {
    if (!use[e]) continue;
    const PoseGraphEdge& edge = edges[e];
    auto* cost = new ceres::AutoDiffCostFunction<EdgeResidual, 6, 4, 3, 4, 3>(new EdgeResidual(residuals[e]));
    // PoseGraphConfig: loops that pass the gate may still be off; odometry may hold a jump.
    ceres::LossFunction* loss = nullptr;
    if (edge.loop) {
      loss = new ceres::HuberLoss(config.loop_huber_sigmas);
    } else if (config.odometry_huber_sigmas > 0) {
      loss = new ceres::HuberLoss(config.odometry_huber_sigmas);
    }
    problem.AddResidualBlock(cost, loss, p.q[edge.i].coeffs().data(), p.t[edge.i].data(), p.q[edge.j].coeffs().data(),
                             p.t[edge.j].data());
  }
  for (std::size_t k = 0; k < p.q.size(); ++k) {
    if (problem.HasParameterBlock(p.q[k].coeffs().data())) problem.SetManifold(p.q[k].coeffs().data(), &quaternion);
  }
  for (std::size_t k : fixed) {
    if (!problem.HasParameterBlock(p.q[k].coeffs().data())) continue;
    problem.SetParameterBlockConstant(p.q[k].coeffs().data());
    problem.SetParameterBlockConstant(p.t[k].data());
  }
  ceres::Solver::Options options;
  options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
  options.max_num_iterations = config.max_iterations;
  options.num_threads = 1;
  options.logging_type = ceres::SILENT;
  ceres::Solver::Summary summary;
  ceres::Solve(options, &problem, &summary);
  return static_cast<int>(summary.iterations.size());
}

}  // namespace

bool loops_agree(const std::vector<Eigen::Isometry3d>& poses, const PoseGraphEdge& a,
                 const PoseGraphEdge& b, const PoseGraphConfig& config) {
  for (const PoseGraphEdge* e : {&a, &b}) {
    if (e->i >= poses.size() || e->j >= poses.size())
      throw splat::Error("loops_agree: a loop names a missing pose");
  }
  const Eigen::Isometry3d by_a = poses[a.i] * a.T_i_j;
  const Eigen::Isometry3d by_b = poses[b.i] * b.T_i_j * poses[b.j].inverse() * poses[a.j];
  const Eigen::Isometry3d difference = by_a.inverse() * by_b;
  const double apart = (poses[a.i].translation() - poses[b.i].translation()).norm() +
                       (poses[a.j].translation() - poses[b.j].translation()).norm();
  return difference.translation().norm() <=
             std::max(config.drift_floor_m, config.drift_per_metre * apart) &&
         Eigen::AngleAxisd(difference.linear()).angle() * 180 / M_PI <=
             std::max(config.drift_floor_deg, config.drift_deg_per_metre * apart);
}

PoseGraphResult optimize_pose_graph(const std::vector<Eigen::Isometry3d>& poses, const std::vector<PoseGraphEdge>& edges,
                                    const std::vector<std::size_t>& fixed, const PoseGraphConfig& config) {
  if (fixed.empty()) throw splat::Error("pose graph: no fixed pose (the graph would float freely)");
  for (std::size_t k : fixed) {
    if (k >= poses.size()) throw splat::Error("pose graph: fixed pose " + std::to_string(k) + " of " + std::to_string(poses.size()));
  }
  std::vector<EdgeResidual> residuals;
  for (std::size_t e = 0; e < edges.size(); ++e) {
    const PoseGraphEdge& edge = edges[e];
    const std::string name = "pose graph edge " + std::to_string(e) + " (" + std::to_string(edge.i) + " -> " + std::to_string(edge.j) + ")";
    if (edge.i >= poses.size() || edge.j >= poses.size() || edge.i == edge.j) {
      throw splat::Error(name + ": names no pair of the " + std::to_string(poses.size()) + " poses");
    }
    if (!edge.T_i_j.matrix().allFinite() || !edge.information.allFinite()) throw splat::Error(name + ": not finite");
    const Eigen::Matrix<double, 6, 6> info = 0.5 * (edge.information + edge.information.transpose());
    const Eigen::LLT<Eigen::Matrix<double, 6, 6>> llt(info);
    if (llt.info() != Eigen::Success) throw splat::Error(name + ": information is not positive definite");
    residuals.push_back({Eigen::Quaterniond(edge.T_i_j.linear()).normalized(), edge.T_i_j.translation(),
                         llt.matrixL().transpose()});
  }
  Parameters start, p;
  for (const auto& T : poses) {
    start.q.push_back(Eigen::Quaterniond(T.linear()).normalized());
    start.t.push_back(T.translation());
  }
  PoseGraphResult result;
  // 1. Odometry alone: where its edges are redundant, their disagreement is the variance
  //    factor (never below 1: the information is never made more confident than measured).
  std::vector<bool> use(edges.size());
  std::size_t odometry_edges = 0;
  for (std::size_t e = 0; e < edges.size(); ++e) use[e] = !edges[e].loop, odometry_edges += use[e];
  result.iterations += solve(start, p, edges, residuals, use, fixed, config);
  const double odometry_chi2 = total(edge_chi2(p, edges, residuals), use);
  result.initial_cost = total(edge_chi2(start, edges, residuals), std::vector<bool>(edges.size(), true));
  const double redundancy = 6.0 * (static_cast<double>(odometry_edges) - static_cast<double>(poses.size() - fixed.size()));
  result.variance_factor = redundancy >= 6 ? std::max(1.0, odometry_chi2 / redundancy) : 1.0;
  for (EdgeResidual& r : residuals) r.sqrt_information /= std::sqrt(result.variance_factor);
  // 2. A loop is accepted where the drift it reveals fits the drift budget for the path between
  //    its keyframes, before solving (against the odometry) and after (against the graph).
  const Parameters odometry = p;
  std::vector<double> path(poses.size(), 0);  // distance travelled to each keyframe
  for (std::size_t k = 1; k < poses.size(); ++k) path[k] = path[k - 1] + (odometry.t[k] - odometry.t[k - 1]).norm();
  auto within_budget = [&](const Parameters& at, std::size_t e) {
    const PoseGraphEdge& edge = edges[e];
    const EdgeResidual& r = residuals[e];
    double error[6];
    EdgeResidual plain = r;
    plain.sqrt_information.setIdentity();
    plain(at.q[edge.i].coeffs().data(), at.t[edge.i].data(), at.q[edge.j].coeffs().data(), at.t[edge.j].data(), error);
    const double travelled = std::abs(path[edge.j] - path[edge.i]);
    const double translation = Eigen::Vector3d(error[0], error[1], error[2]).norm();
    const double degrees = Eigen::Vector3d(error[3], error[4], error[5]).norm() * 180 / M_PI;
    const double factor = edge.confirmed ? config.confirmed_budget_factor : 1.0;
    return translation <=
               factor * std::max(config.drift_floor_m, config.drift_per_metre * travelled) &&
           degrees <=
               factor * std::max(config.drift_floor_deg, config.drift_deg_per_metre * travelled);
  };
  for (std::size_t e = 0; e < edges.size(); ++e) {
    if (edges[e].loop) use[e] = within_budget(odometry, e);
  }
  result.iterations += solve(start, p, edges, residuals, use, fixed, config);
  bool rejected = false;
  for (std::size_t e = 0; e < edges.size(); ++e) {
    if (edges[e].loop && use[e] && !within_budget(p, e)) use[e] = false, rejected = true;
  }
  if (rejected) result.iterations += solve(start, p, edges, residuals, use, fixed, config);
  result.accepted = use;
  result.chi2 = edge_chi2(p, edges, residuals);
  result.final_cost = total(result.chi2, use);
  for (std::size_t k = 0; k < poses.size(); ++k) {
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = p.q[k].normalized().toRotationMatrix();
    T.translation() = p.t[k];
    result.poses.push_back(T);
  }
  return result;
}

}  // namespace tracking
