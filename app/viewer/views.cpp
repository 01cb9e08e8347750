#include "viewer/views.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "splat/error.h"

namespace app {

MapExtent map_extent(const splat::Gaussians& g) {
  const std::size_t n = g.size();
  MapExtent e;
  if (n == 0) return e;
  for (int a = 0; a < 3; ++a) {
    std::vector<float> v(n);
    for (std::size_t i = 0; i < n; ++i) v[i] = g.means[i * 3 + a];
    std::nth_element(v.begin(), v.begin() + static_cast<long>(n / 2), v.end());
    e.center[a] = v[n / 2];
  }
  std::vector<double> d(n);
  for (std::size_t i = 0; i < n; ++i) {
    d[i] = (Eigen::Vector3d(g.means[i * 3], g.means[i * 3 + 1], g.means[i * 3 + 2]) - e.center).norm();
  }
  const std::size_t k = std::min(n - 1, static_cast<std::size_t>(0.9 * static_cast<double>(n)));
  std::nth_element(d.begin(), d.begin() + static_cast<long>(k), d.end());
  e.radius = std::max(d[k], 1e-6);
  return e;
}

namespace {
std::vector<double> parse_numbers(const std::string& text, char sep) {
  std::vector<double> out;
  std::stringstream ss(text);
  for (std::string item; std::getline(ss, item, sep);) {
    char* end = nullptr;
    const double v = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !std::isfinite(v)) return {};
    out.push_back(v);
  }
  return out;
}
}  // namespace

Intrinsics parse_intrinsics(const std::string& text) {
  const std::vector<double> v = parse_numbers(text, ',');
  if (v.size() != 6 || v[0] <= 0 || v[1] <= 0 || v[4] < 1 || v[5] < 1 || v[4] != std::floor(v[4]) ||
      v[5] != std::floor(v[5]) || v[4] > 16384 || v[5] > 16384) {
    throw splat::Error("intrinsics '" + text + "': expected fx,fy,cx,cy,W,H with positive focal lengths and a size of 1..16384");
  }
  return {v[0], v[1], v[2], v[3], static_cast<int>(v[4]), static_cast<int>(v[5])};
}

std::pair<int, int> parse_size(const std::string& text) {
  const std::vector<double> v = parse_numbers(text, 'x');
  if (v.size() != 2 || v[0] < 1 || v[1] < 1 || v[0] > 16384 || v[1] > 16384 || v[0] != std::floor(v[0]) ||
      v[1] != std::floor(v[1])) {
    throw splat::Error("size '" + text + "': expected WxH with W and H in 1..16384, for example 640x480");
  }
  // A render holds some 40 bytes a pixel: 4096x4096 (16.8 Mpixels) stays under 1 GiB.
  if (v[0] * v[1] > kMaxRenderPixels) {
    throw splat::Error("size '" + text + "': " + std::to_string(static_cast<long long>(v[0] * v[1])) +
                       " pixels, expected at most " + std::to_string(static_cast<long long>(kMaxRenderPixels)) +
                       " (4096x4096)");
  }
  return {static_cast<int>(v[0]), static_cast<int>(v[1])};
}

splat::Camera make_camera(const Intrinsics& k, const Eigen::Isometry3d& T_world_cam) {
  splat::Camera c;
  c.fx = k.fx;
  c.fy = k.fy;
  c.cx = k.cx;
  c.cy = k.cy;
  c.width = k.width;
  c.height = k.height;
  c.T_cam_world = T_world_cam.inverse();
  return c;
}

Eigen::Isometry3d look_at(const Eigen::Vector3d& eye, const Eigen::Vector3d& target, const Eigen::Vector3d& up) {
  // OpenCV camera: z looks at the target, y points down (against `up`), x = y cross z.
  const Eigen::Vector3d z = (target - eye).normalized();
  const Eigen::Vector3d x = (-up).cross(z).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
  T_world_cam.linear() << x, y, z;
  T_world_cam.translation() = eye;
  return T_world_cam;
}

std::vector<splat::Camera> orbit_cameras(const MapExtent& extent, int n, int width, int height,
                                         const Eigen::Vector3d& up_in) {
  if (n < 1 || n > kMaxOrbitViews) {
    throw splat::Error("orbit: view count is " + std::to_string(n) + ", expected 1 to " + std::to_string(kMaxOrbitViews));
  }
  if (!(up_in.norm() > 0)) throw splat::Error("orbit: the up vector is zero");
  const Eigen::Vector3d up = up_in.normalized();
  // Two axes spanning the orbit plane.
  const Eigen::Vector3d a = up.unitOrthogonal();
  const Eigen::Vector3d b = up.cross(a);
  const double distance = 2.5 * extent.radius;
  const double elevation = 25.0 * M_PI / 180.0;
  const Intrinsics k{0.8 * width, 0.8 * width, width / 2.0, height / 2.0, width, height};
  std::vector<splat::Camera> cams;
  for (int i = 0; i < n; ++i) {
    const double angle = 2 * M_PI * i / n;
    const Eigen::Vector3d dir = std::cos(elevation) * (std::cos(angle) * a + std::sin(angle) * b) +
                                std::sin(elevation) * up;
    const Eigen::Vector3d eye = extent.center + distance * dir;
    splat::Camera cam = make_camera(k, look_at(eye, extent.center, up));
    cam.near = std::max(1e-4, 0.01 * extent.radius);
    cams.push_back(cam);
  }
  return cams;
}

}  // namespace app
