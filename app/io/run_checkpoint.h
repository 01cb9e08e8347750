// A run's checkpoint: the SLAM system's state between two frames and what the command recorded
// so far, in one file that `gslam reconstruct --resume` continues from. Small fields are JSON;
// the map and its optimizer moments follow as raw little-endian arrays, each with its length.
#pragma once
#include <filesystem>

#include <nlohmann/json.hpp>

#include "slam/slam_system.h"

namespace app {

struct RunCheckpoint {
  SlamSystem::State slam;
  nlohmann::json run = nlohmann::json::object();  // the command's record: input, frames, timings
};

// Written atomically.
void write_run_checkpoint(const std::filesystem::path& path, const RunCheckpoint& checkpoint);
// Throws splat::Error naming the file and the first field that is missing, of the wrong type or
// longer than the bytes that follow it.
RunCheckpoint read_run_checkpoint(const std::filesystem::path& path);

// A pose as the 12 numbers of its 3x4 matrix, row by row, and back (throws on anything else).
nlohmann::json pose_to_json(const Eigen::Isometry3d& T);
Eigen::Isometry3d pose_from_json(const nlohmann::json& j);

}  // namespace app
