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
                              int test_every, const SlamConfig& config);

// --test-every N: frame i (counted from 0) is a held-out test view when (i + 1) % N == 0, so the
// first frame, which defines the world, never is. N = 0: none.
inline bool is_held_out(std::size_t frame, int test_every) {
  return test_every > 0 && (frame + 1) % static_cast<std::size_t>(test_every) == 0;
}

struct RecordedInput {
  std::filesystem::path dataset;
  DatasetOptions options;  // intrinsics as --intrinsics takes them, depth scale, max frames
  nlohmann::json config;   // null where the run did not record it
  int test_every = 0;      // held-out test views (is_held_out)
};
// Throws splat::Error naming `where` (the file it came from) when a field is missing or malformed.
RecordedInput recorded_input(const nlohmann::json& input, const std::string& where);

}  // namespace app
