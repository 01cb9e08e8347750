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
  // A loop another detection agrees with (loops_agree()): judged against
  // PoseGraphConfig::confirmed_budget_factor times the drift budget.
  bool confirmed = false;
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
// kernel at loop_huber_sigmas. Drift is not always gradual: a frame aligned to a person walking
// past moves the whole trajectory after it at once. A loop that a second detection confirms
// (two places, each matched, revealing the same error) is therefore allowed more of it.
struct PoseGraphConfig {
  int max_iterations = 100;
  // Huber kernels, in standard deviations of each edge's information. Loops: an accepted loop
  // may still be off by more than its information says, but at 3 a loop revealing a jump of
  // 20 cm moved the graph by 3 cm. Odometry edges: a jump (a frame aligned to someone walking
  // past) is left in its own edge rather than spread over the whole path, where gradual drift
  // (a focal length error) stays spread. docs/tuning.md has the table both were chosen on.
  double loop_huber_sigmas = 10.0;
  double odometry_huber_sigmas = 30.0;  // 0: none
  // Ten times the drift the odometry shows on the real sequences (docs/measurements.md).
  double drift_per_metre = 0.1, drift_deg_per_metre = 10.0;
  double drift_floor_m = 0.05, drift_floor_deg = 3.0;  // loops between nearby keyframes
  // A confirmed loop's budget, in budgets. Look-alike places that repeat (a symmetric pattern
  // seen twice) reveal errors of a metre and 90 degrees in the generated suite, far outside it.
  double confirmed_budget_factor = 5.0;
};

struct PoseGraphResult {
  std::vector<Eigen::Isometry3d> poses;
  std::vector<bool> accepted;        // per edge: false for the loop edges rejected by the gate
  std::vector<double> chi2;          // per edge: whitened squared residual after the variance factor
  double variance_factor = 1;
  double initial_cost = 0, final_cost = 0;  // sums of chi2 (before the variance factor, at the start)
  int iterations = 0;
};

// Whether loops `a` and `b` reveal the same error in `poses` (camera-to-world, by keyframe): the
// pose `b` gives its newer keyframe, carried to `a`'s newer keyframe through the poses, is where
// `a` puts it, within the drift budget for the distances between their keyframes at either end.
bool loops_agree(const std::vector<Eigen::Isometry3d>& poses, const PoseGraphEdge& a,
                 const PoseGraphEdge& b, const PoseGraphConfig& config = {});

// The optimal poses given the edges, keeping the poses listed in `fixed` (at least one: the
// graph has a free gauge otherwise). Throws splat::Error for an edge naming a pose that does not
// exist, a non-finite measurement, or information that is not symmetric positive definite.
PoseGraphResult optimize_pose_graph(const std::vector<Eigen::Isometry3d>& poses, const std::vector<PoseGraphEdge>& edges,
                                    const std::vector<std::size_t>& fixed, const PoseGraphConfig& config = {});

}  // namespace tracking
