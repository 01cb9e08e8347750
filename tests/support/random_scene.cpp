#include "support/random_scene.h"

#include <cmath>
#include <random>

namespace gslam::test {

template <typename Scalar>
Scene<Scalar> make_random_scene(const SceneOptions& o) {
  std::mt19937 rng(o.seed);
  auto uniform = [&](double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); };
  Scene<Scalar> scene;
  splat::Camera& cam = scene.camera;
  cam.width = o.width;
  cam.height = o.height;
  cam.fx = 0.9 * o.width;
  cam.fy = 0.95 * o.width;
  cam.cx = 0.5 * o.width + 0.7;
  cam.cy = 0.5 * o.height - 0.4;
  const Eigen::Vector3d axis = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
  cam.T_cam_world = Eigen::Translation3d(0.2, -0.1, 0.3) * Eigen::AngleAxisd(0.25, axis);

  splat::GaussiansT<Scalar>& g = scene.gaussians;
  g.sh_degree = o.sh_degree;
  g.resize(static_cast<std::size_t>(o.count));
  const int k = splat::sh_coeff_count(o.sh_degree);
  const Eigen::Isometry3d world_from_cam = cam.T_cam_world.inverse();
  for (int i = 0; i < o.count; ++i) {
    // Centre: a pixel well inside the image, back-projected to a random depth.
    const double u = uniform(0.2, 0.8) * o.width, v = uniform(0.2, 0.8) * o.height;
    const double z = uniform(o.min_depth, o.max_depth);
    const Eigen::Vector3d p_cam((u - cam.cx) / cam.fx * z, (v - cam.cy) / cam.fy * z, z);
    const Eigen::Vector3d p = world_from_cam * p_cam;
    for (int a = 0; a < 3; ++a) {
      g.means[i * 3 + a] = Scalar(p[a]);
      g.log_scales[i * 3 + a] = Scalar(std::log(uniform(o.min_scale, o.max_scale)));
    }
    for (int a = 0; a < 4; ++a) g.rotations[i * 4 + a] = Scalar(uniform(-1, 1));
    g.rotations[i * 4] += Scalar(1.5);  // keeps the quaternion well away from zero
    const double opacity = uniform(o.min_opacity, o.max_opacity);
    g.opacity_logits[i] = Scalar(std::log(opacity / (1 - opacity)));
    for (int c = 0; c < k * 3; ++c) {
      g.sh[i * k * 3 + c] = Scalar(c < 3 ? uniform(-1, 1) : uniform(-0.3, 0.3));
    }
  }
  return scene;
}

template Scene<float> make_random_scene(const SceneOptions&);
template Scene<double> make_random_scene(const SceneOptions&);

}  // namespace gslam::test
