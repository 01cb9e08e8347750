#pragma once
#include <cstdint>
#include <vector>

#include <Eigen/Geometry>

#include "splat/camera.h"

namespace splat {

// One RGB-D observation: colour in [0, 1] and depth in metres (0 = no measurement), both
// [H, W(, 3)], registered to the same pinhole camera. `camera` carries the intrinsics and
// size; its pose is not used.
struct RgbdFrame {
  double timestamp = 0;  // the colour image's
  // When the depth image was taken, relative to the colour image (seconds): cameras that are not
  // synchronized (Kinect v1) pair images up to half a frame apart. 0 once the depth has been
  // moved to the colour's instant (move_depth).
  double depth_time_offset = 0;
  Camera camera;
  std::vector<float> rgb;    // [H, W, 3]
  std::vector<float> depth;  // [H, W]
  // [H, W] or empty (none): non-zero where the pixel shows no part of the static scene (a moving
  // object), left out of tracking and mapping; the value is the caller's reason (the larger wins
  // when downsampled).
  std::vector<uint8_t> ignore;
  // [H, W] or empty (none): class ids from a segmenter, 0 = unknown.
  std::vector<uint16_t> labels;
  int width() const { return camera.width; }
  int height() const { return camera.height; }
};

// The frame at 1/factor resolution: colour averaged over each block, depth averaged over its
// valid pixels (0 if none), a block ignored if any of its pixels is, labelled as its first pixel, intrinsics scaled (pixel centres stay at +0.5). factor >= 1; sizes
// round down.
RgbdFrame downsample(const RgbdFrame& frame, int factor);

// The frame's depth as the camera would have measured it from a pose moved by T_to_from
// (x_to = T_to_from x_from): every measured pixel's point moved and projected again, the
// nearest kept where several land on one pixel; pixels none lands on are left unmeasured.
std::vector<float> reproject_depth(const std::vector<float>& depth, const Camera& intrinsics,
                                   const Eigen::Isometry3d& T_to_from);

// Moves the frame's depth to the colour image's instant, given the camera's motion over
// depth_time_offset: T_colour_depth = T_world_colourcam^-1 T_world_depthcam. In place: only the
// depth changes (and its offset becomes 0), so that colour is never copied for it.
void move_depth_to_colour_time(RgbdFrame& frame, const Eigen::Isometry3d& T_colour_depth);

// The frame's intrinsics with a pose.
Camera posed(const Camera& intrinsics, const Eigen::Isometry3d& T_cam_world);

}  // namespace splat
