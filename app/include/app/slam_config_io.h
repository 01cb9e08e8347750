#pragma once
#include <filesystem>

#include "app/slam.h"

namespace app {

// SLAM settings from a JSON file ({"tracking": {...}, "mapping": {...}, "keyframe_every": N};
// README lists the keys); defaults for an empty path. Throws splat::Error naming the file.
SlamConfig load_slam_config(const std::filesystem::path& path);

}  // namespace app
