// Keyframe pose graph: camera-to-world poses T_k linked by measured relative poses
// Z_ij = T_i^-1 T_j, each with the information of the alignment that measured it. Solved with
// Ceres: the residual of an edge is L^T Log(Z_ij^-1 T_i^-1 T_j) on se(3) (translation first,
// as splat::se3_log), L L^T its information; each pose a unit quaternion (Ceres'
// EigenQuaternionManifold) and a translation.
#pragma once
#include <cstddef>
#include <vector>

#include <Eigen/Geometry>

namespace tracking {

struct PoseGraphEdge {
  std::size_t i = 0, j = 0;
  Eigen::Isometry3d T_i_j = Eigen::Isometry3d::Identity();
  Eigen::Matrix<double, 6, 6> information = Eigen::Matrix<double, 6, 6>::Identity();
  bool loop = false;  // loop edges get a robust kernel and may be rejected
};

// How loops are accepted. The odometry graph is solved alone first; where its edges are
// redundant (a keyframe measured against several), their disagreement scales every information
// (the a posteriori variance factor: dense alignment treats thousands of correlated pixels as
// independent, so its Hessian is right in shape, too confident in scale). Odometry drift is
// systematic, not the independent noise its information describes, so a loop is not judged by
// chi-square against it but by a drift budget: the error the loop reveals must stay within
// drift_per_metre (and drift_deg_per_metre) of the path travelled between its keyframes, both
// against the odometry and after solving with it; a loop outside it is rejected (a place that
// only looks like an earlier one) and the graph solved without it. Accepted loops keep a Huber
// kernel at loop_huber_sigmas.
struct PoseGraphConfig {
  int max_iterations = 100;
  double loop_huber_sigmas = 3.0;
  // Ten times the drift the odometry shows on the real sequences (docs/measurements.md).
  double drift_per_metre = 0.1, drift_deg_per_metre = 10.0;
  double drift_floor_m = 0.05, drift_floor_deg = 3.0;  // loops between nearby keyframes
};

struct PoseGraphResult {
  std::vector<Eigen::Isometry3d> poses;
  std::vector<bool> accepted;        // per edge: false for the loop edges rejected by the gate
  std::vector<double> chi2;          // per edge: whitened squared residual after the variance factor
  double variance_factor = 1;
  double initial_cost = 0, final_cost = 0;  // sums of chi2 (before the variance factor, at the start)
  int iterations = 0;
};

// The optimal poses given the edges, keeping the poses listed in `fixed` (at least one: the
// graph has a free gauge otherwise). Throws splat::Error for an edge naming a pose that does not
// exist, a non-finite measurement, or information that is not symmetric positive definite.
PoseGraphResult optimize_pose_graph(const std::vector<Eigen::Isometry3d>& poses, const std::vector<PoseGraphEdge>& edges,
                                    const std::vector<std::size_t>& fixed, const PoseGraphConfig& config = {});

}  // namespace tracking
