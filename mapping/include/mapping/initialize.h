#pragma once
#include <span>

#include <Eigen/Geometry>

#include "splat/gaussians.h"
#include "splat/rgbd_frame.h"

namespace mapping {

struct SeedConfig {
  int stride = 2;              // one Gaussian per stride x stride pixels
  double opacity = 0.9;        // initial opacity: neighbours overlap into a solid silhouette
  // Isotropic scale: the footprint of `stride` pixels at the measured depth, times this
  // (1 = sigma equal to the spacing, so neighbouring splats overlap without gaps).
  double scale_factor = 1.0;
  int sh_degree = 0;
};

// Gaussians seeded from a frame's depth: one per sampled pixel with a measurement (and, if
// given, mask[p] > 0), at the back-projected point in the world frame, coloured by the pixel
// (SH DC), isotropic, scale from depth / focal. Appends to `map` (same SH degree) and returns
// how many were added.
std::size_t seed_from_depth(const splat::RgbdFrame& frame, const Eigen::Isometry3d& T_world_cam,
                            const SeedConfig& config, splat::Gaussians& map,
                            std::span<const float> mask = {});

}  // namespace mapping
