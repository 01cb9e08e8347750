#pragma once
#include <Eigen/Geometry>
#include <string_view>

namespace splat {

// Pinhole camera, OpenCV convention (x right, y down, looking along +z). Pixel centres are at
// +0.5: pixel (0, 0) covers [0, 1) x [0, 1).
struct Camera {
  double fx = 0, fy = 0;  // focal lengths, pixels
  double cx = 0, cy = 0;  // principal point, pixels
  int width = 0, height = 0;
  // World to camera: p_cam = T_cam_world * p_world.
  Eigen::Isometry3d T_cam_world = Eigen::Isometry3d::Identity();
  double near = 0.01, far = 1e10;  // metres; splats with camera z outside are culled

  // Throws splat::Error naming `where` for non-positive or non-finite intrinsics, an image
  // size outside 1..16384, near/far out of order, or a pose that is not finite and rigid.
  void validate(std::string_view where) const;
};

}  // namespace splat
