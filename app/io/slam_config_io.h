// The SLAM configuration as JSON: {"keyframe_every": 5, ..., "tracking": {...}, "mapping": {...}}.
// `gslam reconstruct --print-config` writes every key with its effective value.
#pragma once
#include <filesystem>
#include <nlohmann/json.hpp>

#include "slam/slam_config.h"

namespace app {

// Settings from a JSON object; keys not given keep their defaults. Throws splat::Error naming
// the key path for an unknown key, a wrong type, a non-integral or out-of-range integer, a
// non-object document or a section that is not an object, and whatever SlamConfig::validate()
// refuses ("mapping.window: expected an integer >= 1, got 0").
SlamConfig slam_config_from_json(const nlohmann::json& document);
// Every setting, in the form slam_config_from_json() reads back unchanged.
nlohmann::json slam_config_to_json(const SlamConfig& config);
// slam_config_from_json() of a file (defaults for an empty path); errors start with the path.
SlamConfig load_slam_config(const std::filesystem::path& path);

}  // namespace app
