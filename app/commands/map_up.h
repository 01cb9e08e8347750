// Which way is up for a map that gslam renders or shows.
#pragma once
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "splat/gaussians.h"

namespace app {

struct MapUp {
  Eigen::Vector3d up;  // unit, in the map's frame
  std::string source;  // where it came from, for the command's output
};

// `given` (--up) when there is one, else the "world_up" of the summary.json beside `map_file`
// (a run's map.ply or map.glb, both in the run's world frame), else estimated from `poses`
// (viewer/views.h estimate_world_up: the floor's normal, else the cameras' up), else +z.
// Throws splat::Error for a given vector that is zero or not finite.
MapUp choose_map_up(const std::optional<Eigen::Vector3d>& given, const std::filesystem::path& map_file,
                    const std::vector<Eigen::Isometry3d>& poses, const splat::Gaussians& map);

}  // namespace app
