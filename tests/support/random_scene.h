#pragma once
#include <cstdint>

#include "splat/camera.h"
#include "splat/gaussians.h"

namespace gslam::test {

struct SceneOptions {
  uint32_t seed = 1;
  int count = 8;
  int sh_degree = 3;
  int width = 64, height = 48;
  // Smooth scenes for gradient checks: opacities in [0.3, 0.8] (far from the 1/255 skip and
  // the 0.999 cap) and few enough splats that transmittance never reaches the 1e-4 stop.
  double min_opacity = 0.3, max_opacity = 0.8;
  double min_depth = 3.0, max_depth = 5.0;
  double min_scale = 0.04, max_scale = 0.15;  // metres: a few to ~15 px at fx = 60
};

template <typename Scalar>
struct Scene {
  splat::GaussiansT<Scalar> gaussians;
  splat::Camera camera;
};

// Random splats whose centres project inside the image (away from its border), seen by a camera
// with a generic (non-identity) pose. Deterministic for a seed.
template <typename Scalar>
Scene<Scalar> make_random_scene(const SceneOptions& options);

}  // namespace gslam::test
