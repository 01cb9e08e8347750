// What a run read (summary.json "input": dataset, format, camera, depth units, frames, SLAM
// configuration): written by reconstruct, read back by eval and by reconstruct --resume.
#pragma once
#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

#include "datasets/dataset.h"
#include "slam/slam_config.h"

namespace app {

nlohmann::json run_input_json(const std::filesystem::path& input, const Dataset& dataset, int max_frames,
                              const SlamConfig& config);

struct RecordedInput {
  std::filesystem::path dataset;
  DatasetOptions options;  // intrinsics as --intrinsics takes them, depth scale, max frames
  nlohmann::json config;   // null where the run did not record it
};
// Throws splat::Error naming `where` (the file it came from) when a field is missing or malformed.
RecordedInput recorded_input(const nlohmann::json& input, const std::string& where);

}  // namespace app
