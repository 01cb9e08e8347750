#include "viewer/views.h"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
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
  return orbit_at_camera_height(extent, poses, n, k, camera_up(poses));
}

std::vector<splat::Camera> orbit_at_camera_height(const MapExtent& extent, const std::vector<Eigen::Isometry3d>& poses,
                                                  int n, const Intrinsics& k, const Eigen::Vector3d& up_in) {
  if (poses.empty()) throw splat::Error("orbit: no camera poses");
  if (!(up_in.norm() > 0) || !up_in.allFinite()) throw splat::Error("orbit: the up vector is zero or not finite");
  const Eigen::Vector3d up = up_in.normalized();
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

namespace {

// splitmix64: a fixed-seed generator whose draws are the same with every standard library.
struct SplitMix64 {
  uint64_t state;
  uint64_t next() {
    uint64_t z = (state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  std::size_t below(std::size_t n) { return static_cast<std::size_t>(next() % n); }
};

// A plane normal . p = offset, its normal on the cameras' side.
struct Plane {
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();
  double offset = 0;
  double distance(const Eigen::Vector3d& p) const { return normal.dot(p) - offset; }
};

std::size_t count_inliers(const std::vector<Eigen::Vector3d>& points, const Plane& plane, double tolerance) {
  std::size_t n = 0;
  for (const auto& p : points) n += std::abs(plane.distance(p)) < tolerance;
  return n;
}

// Least-squares plane (the smallest principal axis) through the points within `tolerance` of
// `plane`, repeated so that points of a neighbouring surface the first guess grazed drop out.
Plane refit(const std::vector<Eigen::Vector3d>& points, Plane plane, double tolerance) {
  for (int iteration = 0; iteration < 5; ++iteration) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    std::size_t n = 0;
    for (const auto& p : points) {
      if (std::abs(plane.distance(p)) < tolerance) mean += p, ++n;
    }
    if (n < 3) break;
    mean /= static_cast<double>(n);
    Eigen::Matrix3d scatter = Eigen::Matrix3d::Zero();
    for (const auto& p : points) {
      if (std::abs(plane.distance(p)) < tolerance) scatter += (p - mean) * (p - mean).transpose();
    }
    Eigen::Vector3d normal = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(scatter).eigenvectors().col(0);
    if (normal.dot(plane.normal) < 0) normal = -normal;
    plane.normal = normal.normalized();
    plane.offset = plane.normal.dot(mean);
  }
  return plane;
}

}  // namespace

WorldUp estimate_world_up(const std::vector<Eigen::Isometry3d>& poses, const splat::Gaussians& map) {
  if (poses.empty()) throw splat::Error("estimate_world_up: no camera poses");
  WorldUp result;
  result.up = camera_up(poses);
  // The means, evenly strided down to a bounded count (the cost is iterations x points).
  const std::size_t n = map.size();
  const std::size_t stride = std::max<std::size_t>(1, (n + kWorldUpMaxPoints - 1) / kWorldUpMaxPoints);
  std::vector<Eigen::Vector3d> points;
  for (std::size_t i = 0; i < n; i += stride) {
    const Eigen::Vector3d p(map.means[i * 3], map.means[i * 3 + 1], map.means[i * 3 + 2]);
    if (p.allFinite()) points.push_back(p);
  }
  constexpr std::size_t kMinPoints = 100;  // fewer cannot tell a plane from chance
  if (points.size() < kMinPoints) return result;

  // Scale: the 90th percentile distance from the median, as map_extent measures it.
  Eigen::Vector3d center;
  for (int a = 0; a < 3; ++a) {
    std::vector<double> v(points.size());
    for (std::size_t i = 0; i < points.size(); ++i) v[i] = points[i][a];
    std::nth_element(v.begin(), v.begin() + static_cast<long>(v.size() / 2), v.end());
    center[a] = v[v.size() / 2];
  }
  std::vector<double> d(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) d[i] = (points[i] - center).norm();
  const std::size_t k90 = static_cast<std::size_t>(0.9 * static_cast<double>(d.size() - 1));
  std::nth_element(d.begin(), d.begin() + static_cast<long>(k90), d.end());
  const double radius = d[k90];
  if (!(radius > 0)) return result;
  // A surface's means lie within a percent of the map's size of its plane (depth noise, splat
  // thickness); a room of 5 m gives 2.5 cm, still well apart from a table top.
  const double tolerance = 0.01 * radius;
  const std::size_t min_inliers = std::max(kMinPoints, points.size() / 20);  // 5% of the means
  const double min_cos = std::cos(30.0 * M_PI / 180.0);  // the cameras' up is off by less
  constexpr double kCamerasAbove = 0.8;                  // a floor lies below most cameras

  const Eigen::Vector3d camera_up_dir = result.up;
  // Mean height of the cameras above `plane`, or NaN unless most of them are above it.
  const auto camera_height = [&](const Plane& plane) {
    double sum = 0;
    std::size_t above = 0;
    for (const auto& T : poses) {
      const double h = plane.distance(T.translation());
      sum += h;
      above += h > tolerance;
    }
    if (static_cast<double>(above) < kCamerasAbove * static_cast<double>(poses.size())) return std::nan("");
    return sum / static_cast<double>(poses.size());
  };
  const auto acceptable = [&](const Plane& plane, std::size_t inliers) {
    return plane.normal.dot(camera_up_dir) >= min_cos && inliers >= min_inliers && std::isfinite(camera_height(plane));
  };

  // RANSAC, each sample drawn from one cell of a grid a tenth of the map's size: three means
  // that near each other lie on one surface far more often than three drawn anywhere, so a floor
  // holding a tenth of the means is sampled in about one draw of ten, not one of a thousand.
  const double cell = 0.1 * radius;
  std::vector<std::pair<uint64_t, std::size_t>> keyed(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) {
    uint64_t key = 0;
    for (int a = 0; a < 3; ++a) {
      const double c = std::clamp(std::floor((points[i][a] - center[a]) / cell), -1e6, 1e6);
      key = key * 2097152u + static_cast<uint64_t>(static_cast<int64_t>(c) + 1048576);  // 21 bits an axis
    }
    keyed[i] = {key, i};
  }
  std::sort(keyed.begin(), keyed.end());
  std::vector<std::size_t> cell_begin(keyed.size()), cell_end(keyed.size());  // by position in `keyed`
  for (std::size_t b = 0; b < keyed.size();) {
    std::size_t e = b;
    while (e < keyed.size() && keyed[e].first == keyed[b].first) ++e;
    for (std::size_t j = b; j < e; ++j) cell_begin[j] = b, cell_end[j] = e;
    b = e;
  }
  struct Hypothesis {
    Plane plane;
    std::size_t inliers = 0;
    double height = 0;  // the cameras' mean height above it
    std::array<std::size_t, 3> sample{};
    bool explained = false;  // its sample lies on a plane already fitted
  };
  std::vector<Hypothesis> hypotheses;
  SplitMix64 rng{0x5EEDu};
  constexpr int kIterations = 1000;  // ~100 draws on a floor holding 10% of the means
  for (int it = 0; it < kIterations; ++it) {
    const std::size_t j = rng.below(keyed.size());
    const std::size_t b = cell_begin[j], count = cell_end[j] - b;
    if (count < 3) continue;
    const std::size_t i0 = keyed[j].second, i1 = keyed[b + rng.below(count)].second,
                      i2 = keyed[b + rng.below(count)].second;
    if (i0 == i1 || i1 == i2 || i0 == i2) continue;
    Eigen::Vector3d normal = (points[i1] - points[i0]).cross(points[i2] - points[i0]);
    if (!(normal.norm() > 1e-12)) continue;
    normal.normalize();
    if (normal.dot(camera_up_dir) < 0) normal = -normal;
    if (normal.dot(camera_up_dir) < min_cos) continue;  // a wall
    Hypothesis h;
    h.plane = {normal, normal.dot(points[i0])};
    h.inliers = count_inliers(points, h.plane, tolerance);
    if (h.inliers < min_inliers) continue;
    h.height = camera_height(h.plane);
    if (!std::isfinite(h.height)) continue;  // above the cameras, or among them
    h.sample = {i0, i1, i2};
    hypotheses.push_back(h);
  }
  if (hypotheses.empty()) return result;

  // The largest plane first, then any plane at least half its size lying lower: a floor rather
  // than a table top. Each fitted plane explains the samples on it, so every plane is fitted once.
  std::size_t largest = 0;
  for (const auto& h : hypotheses) largest = std::max(largest, h.inliers);
  std::optional<Plane> floor;
  double floor_height = -std::numeric_limits<double>::infinity();
  constexpr int kMaxFits = 16;
  for (int fit = 0; fit < kMaxFits; ++fit) {
    Hypothesis* next = nullptr;
    for (auto& h : hypotheses) {
      if (h.explained || 2 * h.inliers < largest || h.height <= floor_height + 3 * tolerance) continue;
      if (!next || h.inliers > next->inliers) next = &h;
    }
    if (!next) break;
    const Plane plane = refit(points, next->plane, tolerance);
    for (auto& h : hypotheses) {
      h.explained = h.explained || std::all_of(h.sample.begin(), h.sample.end(), [&](std::size_t i) {
                      return std::abs(plane.distance(points[i])) < tolerance;
                    });
    }
    next->explained = true;
    const double height = camera_height(plane);
    if (acceptable(plane, count_inliers(points, plane, tolerance)) && height > floor_height) {
      floor = plane;
      floor_height = height;
    }
  }
  if (floor) {
    result.up = floor->normal;
    result.source = WorldUp::Source::kFloorPlane;
  }
  return result;
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
