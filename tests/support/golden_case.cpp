#include "support/golden_case.h"

#include <cmath>

namespace gslam::test {

GoldenCase load_golden_case(const std::filesystem::path& path) {
  GoldenCase g;
  g.tensors = read_safetensors(path);
  g.gaussians.sh_degree = 3;
  g.gaussians.means = g.tensor("means").values;
  g.gaussians.log_scales = g.tensor("scales").values;
  g.gaussians.rotations = g.tensor("quats").values;
  g.gaussians.opacity_logits = g.tensor("opacities").values;
  g.gaussians.sh = g.tensor("coeffs").values;
  // W = 123, H = 82, fx = fy = 0.5 W / tan(45 deg), principal point at the centre,
  // identity rotation, camera centre (0.123, 0.456, -8.0).
  g.camera.width = 123;
  g.camera.height = 82;
  g.camera.fx = g.camera.fy = 0.5 * 123 / std::tan(M_PI / 4);
  g.camera.cx = 123 / 2.0;
  g.camera.cy = 82 / 2.0;
  g.camera.T_cam_world = Eigen::Translation3d(-0.123, -0.456, 8.0) * Eigen::Isometry3d::Identity();
  g.camera.near = 0.01;
  g.camera.far = 1e12;
  return g;
}

}  // namespace gslam::test
