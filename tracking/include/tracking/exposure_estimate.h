// The colour camera's exposure time, measured from the frames themselves, for the blur-aware
// depth weight (rgbd_odometry.h). Motion blur smears a frame along the direction the image
// moves, so its intensity gradients fade along that direction and not across it; how fast they
// fade with the camera's angular rate says how long the shutter stays open. Cameras differ by an
// order of magnitude here (a bright scene at 1/200 s, a dim kitchen at 1/15 s), and no dataset
// says which.
#pragma once
#include <array>
#include <deque>
#include <vector>

#include <Eigen/Core>

#include "tracking/rgbd_odometry.h"

namespace tracking {

// A frame's finest-level gradient energy along the unit image direction `direction` over its
// energy across it: about 1 for a sharp frame of an isotropic scene, lower when blurred along
// `direction`.
double directional_sharpness(const OdometryFrame& frame, const Eigen::Vector2d& direction);

// Fits, over the last tracked frames, 1 / sharpness = a + s * b, where b is the blur in
// finest-level pixels that the frame's angular rate would smear over the nominal exposure
// (config.exposure). The scene's own anisotropy sits in a; s / a is how fast the frames fade per
// pixel of nominal blur, which grows with the true exposure. config.fade_per_blur_px is s / a
// at the nominal exposure, so the exposure is config.exposure * (s / a) / fade_per_blur_px.
class ExposureEstimate {
 public:
  explicit ExposureEstimate(const OdometryConfig& config) : config_(config) {}
  // A tracked frame and the camera's angular velocity when it was taken (rad/s, camera axes).
  void observe(const OdometryFrame& frame, const Eigen::Vector3d& angular_velocity);
  // Seconds: config.exposure until the frames seen span enough motion to say, then the fit,
  // within [exposure / 4, exposure * 16].
  double exposure() const;
  // (nominal blur, 1 / sharpness) of the frames it holds, oldest first: for checkpoints.
  std::vector<std::array<double, 2>> samples() const { return {samples_.begin(), samples_.end()}; }
  void restore(const std::vector<std::array<double, 2>>& samples);

 private:
  const OdometryConfig& config_;
  std::deque<std::array<double, 2>> samples_;
};

}  // namespace tracking
