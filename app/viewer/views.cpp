#include "viewer/views.h"

#include <Eigen/Eigenvalues>

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

namespace {

void check_view_count(int n) {
  if (n < 1 || n > kMaxOrbitViews) {
    throw splat::Error("orbit: view count is " + std::to_string(n) + ", expected 1 to " + std::to_string(kMaxOrbitViews));
  }
}

// n cameras on a circle about `center` in the plane normal to `up` (unit), at `radius` from the
// axis and `height` along it, looking at the centre.
std::vector<splat::Camera> circle_cameras(const Eigen::Vector3d& center, const Eigen::Vector3d& up, double radius,
                                          double height, int n, const Intrinsics& k, double near) {
  check_view_count(n);
  const Eigen::Vector3d a = up.unitOrthogonal(), b = up.cross(a);  // the orbit plane
  std::vector<splat::Camera> cams;
  for (int i = 0; i < n; ++i) {
    const double angle = 2 * M_PI * i / n;
    const Eigen::Vector3d eye = center + radius * (std::cos(angle) * a + std::sin(angle) * b) + height * up;
    splat::Camera cam = make_camera(k, look_at(eye, center, up));
    cam.near = near;
    cams.push_back(cam);
  }
  return cams;
}

}  // namespace

std::vector<splat::Camera> orbit_cameras(const MapExtent& extent, int n, int width, int height,
                                         const Eigen::Vector3d& up_in) {
  check_view_count(n);
  if (!(up_in.norm() > 0)) throw splat::Error("orbit: the up vector is zero");
  const double distance = 2.5 * extent.radius, elevation = 25.0 * M_PI / 180.0;
  const Intrinsics k{0.8 * width, 0.8 * width, width / 2.0, height / 2.0, width, height};
  return circle_cameras(extent.center, up_in.normalized(), distance * std::cos(elevation), distance * std::sin(elevation),
                        n, k, std::max(1e-4, 0.01 * extent.radius));
}

Eigen::Vector3d camera_up(const std::vector<Eigen::Isometry3d>& poses) {
  Eigen::Vector3d image_up = Eigen::Vector3d::Zero();
  Eigen::Matrix3d rights = Eigen::Matrix3d::Zero();
  for (const auto& T : poses) {
    image_up -= T.linear().col(1);
    rights += T.linear().col(0) * T.linear().col(0).transpose();
  }
  if (!(image_up.norm() > 1e-9)) throw splat::Error("the cameras agree on no up direction");
  image_up.normalize();
  // Hand-held and robot cameras rarely roll: their x axes lie in the horizontal plane, so up is
  // the direction most normal to all of them. Where they all point one way (no turn), that
  // leaves a plane: the image-up direction within it.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> solver(rights);
  const Eigen::Vector3d& values = solver.eigenvalues();
  Eigen::Vector3d up;
  if (values[1] > 0.05 * values[2]) {
    up = solver.eigenvectors().col(0);
  } else {
    const Eigen::Vector3d right = solver.eigenvectors().col(2);
    up = (image_up - image_up.dot(right) * right).normalized();
  }
  return up.dot(image_up) < 0 ? -up : up;
}

std::vector<splat::Camera> orbit_at_camera_height(const MapExtent& extent, const std::vector<Eigen::Isometry3d>& poses,
                                                  int n, const Intrinsics& k) {
  if (poses.empty()) throw splat::Error("orbit: no camera poses");
  const Eigen::Vector3d up = camera_up(poses);
  // The scene's centre: the point nearest every camera's line of sight (what they looked at),
  // unless the lines are near parallel or meet far outside the map.
  Eigen::Matrix3d normal = Eigen::Matrix3d::Zero();
  Eigen::Vector3d rhs = Eigen::Vector3d::Zero();
  for (const auto& T : poses) {
    const Eigen::Vector3d d = T.linear().col(2);
    const Eigen::Matrix3d across = Eigen::Matrix3d::Identity() - d * d.transpose();
    normal += across;
    rhs += across * T.translation();
  }
  Eigen::Vector3d center = extent.center;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> conditioning(normal);
  if (conditioning.eigenvalues()[0] > 1e-3 * conditioning.eigenvalues()[2]) {
    const Eigen::Vector3d looked_at = normal.ldlt().solve(rhs);
    if ((looked_at - extent.center).norm() < 2 * extent.radius) center = looked_at;
  }
  double height = 0, radius = 0;
  for (const auto& T : poses) {
    const Eigen::Vector3d d = T.translation() - center;
    height += d.dot(up);
    radius += (d - d.dot(up) * up).norm();
  }
  height /= static_cast<double>(poses.size());
  radius = std::max(radius / static_cast<double>(poses.size()), 0.1 * extent.radius);
  return circle_cameras(center, up, radius, height, n, k, std::max(1e-4, 0.01 * extent.radius));
}

std::vector<Eigen::Isometry3d> novel_path(const std::vector<Eigen::Isometry3d>& poses, int views,
                                          const Eigen::Vector3d& offset_cam, int half_window) {
  check_view_count(views);
  if (poses.empty()) throw splat::Error("path: no camera poses");
  const int m = static_cast<int>(poses.size());
  // Moving average: positions, and rotations as the normalized sum of sign-aligned quaternions.
  std::vector<Eigen::Vector3d> position(poses.size());
  std::vector<Eigen::Quaterniond> rotation(poses.size());
  for (int i = 0; i < m; ++i) {
    const Eigen::Quaterniond centre(poses[static_cast<std::size_t>(i)].linear());
    Eigen::Vector3d p = Eigen::Vector3d::Zero();
    Eigen::Vector4d q = Eigen::Vector4d::Zero();
    int count = 0;
    for (int j = std::max(0, i - half_window); j <= std::min(m - 1, i + half_window); ++j, ++count) {
      const Eigen::Isometry3d& T = poses[static_cast<std::size_t>(j)];
      p += T.translation();
      Eigen::Quaterniond r(T.linear());
      if (r.dot(centre) < 0) r.coeffs() *= -1;
      q += r.coeffs();
    }
    position[static_cast<std::size_t>(i)] = p / count;
    rotation[static_cast<std::size_t>(i)] = Eigen::Quaterniond(q.normalized());
  }
  std::vector<Eigen::Isometry3d> path;
  for (int v = 0; v < views; ++v) {
    // Half a step off the recorded poses, so that no view sits where a frame was taken.
    const double s = views == 1 ? 0.5 * (m - 1) : (m - 1) * (v + 0.5) / views;
    const std::size_t i = static_cast<std::size_t>(std::floor(s));
    const std::size_t j = std::min(i + 1, poses.size() - 1);
    const double t = s - static_cast<double>(i);
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = rotation[i].slerp(t, rotation[j]).toRotationMatrix();
    T.translation() = (1 - t) * position[i] + t * position[j] + T.linear() * offset_cam;
    path.push_back(T);
  }
  return path;
}

}  // namespace app
