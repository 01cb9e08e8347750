#pragma once
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "splat/rasterizer.h"
#include "splat/rgbd_frame.h"

namespace tracking {

struct TrackingConfig {
  // Coarse to fine: downsampling factors, coarsest first, each with its iteration budget. Two
  // levels held wider motion (teddy's every third frame) where one lost it; a full-resolution
  // level cost time without lowering ATE.
  std::vector<int> pyramid = {4, 2};
  std::vector<int> iterations = {10, 10};
  // First-order warm-up on the coarsest level before Gauss-Newton: Adam steps of these sizes
  // (metres, radians) cross the wide basin where the linear model of textured residuals is
  // poor; Gauss-Newton then converges in a few steps. 0 iterations disables it.
  int warmup_iterations = 0;
  double warmup_step_translation = 2e-3;
  double warmup_step_rotation = 2e-3;
  // Residuals are divided by these noise levels, so both terms are unitless.
  // metres. Measured on TUM teddy: at 0.02 the depth term held poses near their start (a 2.2 cm
  // motion came out as 0.9 cm); at 0.1 to 0.2 the same frame tracked to 2.5 mm.
  double depth_sigma = 0.1;
  double color_sigma = 0.1;   // colour units in [0, 1]
  double color_weight = 0.5;  // relative weight of the photometric term
  // The photometric term only enters levels downsampled by at most this factor. Coarser levels
  // align depth alone: measured on the donut, colour there leads a 10 cm / 10 deg start into a
  // wrong minimum (0.25 m off), while depth alone converges.
  int color_max_factor = 1024;  // default: every level
  double huber = 2.0;         // Huber threshold in noise units (robust to outliers)
  double alpha_threshold = 0.95;  // pixels whose rendered silhouette is reliable
  // Residual rejection: depth residuals above this many times the median are ignored.
  double outlier_factor = 10.0;
  // A level ends when an accepted step moves less than this (metres, radians): 0.3 mm / 0.3 mrad
  // is below what depth noise resolves, and stopping there took a third off tracking time.
  double min_step_translation = 3e-4;
  double min_step_rotation = 3e-4;
  // Failure: too few usable pixels, or a large final depth residual.
  double min_overlap = 0.2;           // fraction of valid-depth pixels with a reliable render
  double max_median_residual = 0.10;  // metres (Kinect depth noise reaches ~5 cm at 4 m)
  // Throws splat::Error naming the first field out of range, as `prefix` + field name.
  void validate(const std::string& prefix = "TrackingConfig.") const;
};

struct TrackingResult {
  Eigen::Isometry3d T_cam_world = Eigen::Isometry3d::Identity();
  bool converged = false;
  std::string reason;  // why not converged (empty when converged)
  int iterations = 0;  // warm-up steps plus accepted Gauss-Newton steps, all levels
  int renders = 0;     // forward passes, all levels
  double final_cost = 0;
  double overlap = 0;                // finest level
  double median_depth_residual = 0;  // metres, finest level
};

// Optimizes the camera pose of `frame` against a fixed map through the rasterizer, starting
// from `initial_T_cam_world`: Levenberg-Marquardt on se(3) (left updates T <- exp(delta) T)
// with the rasterizer's analytic pose Jacobian, over pixels with measured depth and a
// reliable silhouette, Huber-weighted depth and colour residuals, depth outliers rejected,
// coarse to fine, stopping early once steps are tiny. A bad fit is reported in the result,
// never thrown; invalid input throws splat::Error.
TrackingResult track_frame(splat::Rasterizer& rasterizer, const splat::GaussiansView& map,
                           const splat::RgbdFrame& frame,
                           const Eigen::Isometry3d& initial_T_cam_world,
                           const TrackingConfig& config);

}  // namespace tracking
