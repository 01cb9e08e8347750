#pragma once
#include <filesystem>
#include <vector>

#include <Eigen/Geometry>

namespace app {

struct StampedPose {
  double timestamp = 0;                                          // seconds
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();  // camera to world
};

// Reads a TUM-format trajectory: '#' comments, then `timestamp tx ty tz qx qy qz qw` per line
// (camera to world, Hamilton quaternion, w last). Quaternions are normalized; one far from unit
// length (|q| outside [0.9, 1.1]) or a line without 8 finite numbers is an error naming the line.
std::vector<StampedPose> read_tum_trajectory(const std::filesystem::path& path);

// Writes poses in the same format with full precision, atomically.
void write_tum_trajectory(const std::filesystem::path& path, const std::vector<StampedPose>& poses);

}  // namespace app
