#pragma once
#include <cstddef>
#include <optional>
#include <string>

#include "splat/camera.h"
#include "splat/gaussians.h"

namespace gslam::bench {

// The named benchmark workload every backend reports on: the real donut map
// (../shared/data/v3dg_donut_3dgs_ply/fused.ply, 45,624 Gaussians) replicated with jitter
// (normal, sigma = 1% of the map's 90th-percentile radius around its median centre) to `count`
// Gaussians, seen at width x height with fx = fy = 525 (scaled with width from 640), principal
// point at the image centre, identity rotation, from centre - (0, 0, 2 radius).
struct Workload {
  splat::Gaussians gaussians;
  splat::Camera camera;
};

// nullopt when the shared data is absent.
std::optional<Workload> donut_workload(std::size_t count, int width = 640, int height = 480);

std::string shared_data_dir();

}  // namespace gslam::bench
