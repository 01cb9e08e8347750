#include "donut_workload.h"

#include <filesystem>
#include <random>

#include "io/ply_io.h"
#include "viewer/views.h"

namespace gslam::bench {

std::string shared_data_dir() { return GSLAM_SHARED_DATA_DIR; }

std::optional<Workload> donut_workload(std::size_t count, int width, int height) {
  const std::filesystem::path path = std::filesystem::path(shared_data_dir()) / "v3dg_donut_3dgs_ply/fused.ply";
  if (!std::filesystem::exists(path)) return std::nullopt;
  const splat::Gaussians donut = app::read_ply(path).gaussians;
  const app::MapExtent extent = app::map_extent(donut);
  Workload w;
  splat::Gaussians& g = w.gaussians;
  g.sh_degree = donut.sh_degree;
  g.resize(count);
  const std::size_t n = donut.size();
  const std::size_t k = static_cast<std::size_t>(splat::sh_coeff_count(g.sh_degree)) * 3;
  std::mt19937 rng(2024);
  std::normal_distribution<float> jitter(0.f, static_cast<float>(0.01 * extent.radius));
  for (std::size_t i = 0; i < count; ++i) {
    const std::size_t s = i % n;
    const bool copy = i >= n;  // the original map first, then jittered copies
    for (int a = 0; a < 3; ++a) {
      g.means[i * 3 + a] = donut.means[s * 3 + a] + (copy ? jitter(rng) : 0.f);
      g.log_scales[i * 3 + a] = donut.log_scales[s * 3 + a];
    }
    for (int a = 0; a < 4; ++a) g.rotations[i * 4 + a] = donut.rotations[s * 4 + a];
    g.opacity_logits[i] = donut.opacity_logits[s];
    for (std::size_t c = 0; c < k; ++c) g.sh[i * k + c] = donut.sh[s * k + c];
  }
  splat::Camera& cam = w.camera;
  cam.width = width;
  cam.height = height;
  cam.fx = cam.fy = 525.0 * width / 640.0;
  cam.cx = width / 2.0;
  cam.cy = height / 2.0;
  const Eigen::Vector3d eye = extent.center - Eigen::Vector3d(0, 0, 2 * extent.radius);
  cam.T_cam_world = Eigen::Translation3d(-eye) * Eigen::Isometry3d::Identity();
  return w;
}

}  // namespace gslam::bench
