#include "mapping/initialize.h"

#include <cmath>
#include <string>

#include "splat/error.h"

namespace mapping {

std::size_t seed_from_depth(const splat::RgbdFrame& frame, const Eigen::Isometry3d& T_world_cam,
                            const SeedConfig& c, splat::Gaussians& map, std::span<const float> mask) {
  if (c.stride < 1) throw splat::Error("seed_from_depth: stride is " + std::to_string(c.stride));
  if (!map.empty() && map.sh_degree != c.sh_degree) throw splat::Error("seed_from_depth: SH degree differs from the map's");
  map.sh_degree = c.sh_degree;
  const splat::Camera& k = frame.camera;
  const int w = frame.width(), h = frame.height();
  if (!mask.empty() && mask.size() != static_cast<std::size_t>(w) * h) throw splat::Error("seed_from_depth: mask size differs from the frame");
  constexpr double kShC0 = 0.28209479177387814;
  const double logit = std::log(c.opacity / (1 - c.opacity));
  const int coeffs = splat::sh_coeff_count(c.sh_degree) * 3;
  const std::size_t first = map.size();
  std::size_t added = 0;
  for (int y = c.stride / 2; y < h; y += c.stride) {
    for (int x = c.stride / 2; x < w; x += c.stride) {
      const std::size_t p = static_cast<std::size_t>(y) * w + x;
      const double z = frame.depth[p];
      if (!(z > 0) || (!mask.empty() && !(mask[p] > 0))) continue;
      const Eigen::Vector3d p_cam((x + 0.5 - k.cx) / k.fx * z, (y + 0.5 - k.cy) / k.fy * z, z);
      const Eigen::Vector3d p_world = T_world_cam * p_cam;
      const std::size_t i = first + added++;
      map.resize(i + 1);
      const double scale = c.scale_factor * c.stride * z / k.fx;
      for (int a = 0; a < 3; ++a) {
        map.means[i * 3 + a] = static_cast<float>(p_world[a]);
        map.log_scales[i * 3 + a] = static_cast<float>(std::log(scale));
      }
      map.rotations[i * 4] = 1;
      map.opacity_logits[i] = static_cast<float>(logit);
      for (int ch = 0; ch < 3; ++ch) {
        map.sh[i * static_cast<std::size_t>(coeffs) + ch] = static_cast<float>((frame.rgb[p * 3 + ch] - 0.5) / kShC0);
      }
    }
  }
  return added;
}

}  // namespace mapping
