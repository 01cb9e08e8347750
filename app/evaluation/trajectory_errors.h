#pragma once
#include <vector>

#include <Eigen/Geometry>

#include "io/trajectory.h"

namespace app {

struct TrajectoryErrors {
  std::size_t matched = 0;            // estimated poses with ground truth within 0.02 s
  double ate_rmse = 0;                // metres, after alignment
  double ate_mean = 0, ate_max = 0;
  double scale = 1;                   // from the alignment (1 unless sim3)
  std::vector<double> times;          // per matched pose
  std::vector<double> ate_errors;     // metres, per matched pose
  std::vector<Eigen::Vector3d> aligned_estimate, truth;  // per matched pose, for plots
  double rpe_translation_rmse = 0;    // metres over `rpe_delta` seconds
  double rpe_rotation_rmse_deg = 0;
  std::size_t rpe_pairs = 0;
};

// TUM benchmark conventions: associate by nearest timestamp (max 0.02 s), align the estimated
// positions to the truth with Horn/Umeyama (rigid, or similarity with `sim3`), report the RMSE
// of the position differences; RPE over pairs `rpe_delta` seconds apart (TUM's evaluate_rpe,
// translational and rotational). Throws splat::Error with fewer than 3 matched poses.
TrajectoryErrors evaluate_trajectory(const std::vector<StampedPose>& estimate,
                                     const std::vector<StampedPose>& truth, bool sim3 = false,
                                     double rpe_delta = 1.0);

}  // namespace app
