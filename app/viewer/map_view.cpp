#include "viewer/map_view.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "splat/error.h"
#include "viewer/live_view.h"

namespace app {
namespace {

constexpr double kOrbitRadiansPerPixel = 0.01;
// Orbit elevation limit: at the pole, "up" in the image would be undefined.
constexpr double kMaxElevation = 85.0 * M_PI / 180.0;
constexpr double kZoomPerStep = 0.9;
// Frustum depth as a fraction of the radius holding map and cameras: visible in the overview,
// small beside the map.
constexpr double kFrustumDepth = 0.06;
// Frusta whose centre is nearer the view than this many frustum depths are left out.
constexpr double kMarkerClearance = 3;

// The overview's intrinsics (as orbit_cameras: fx = 0.8 * width).
Intrinsics default_intrinsics() {
  return {0.8 * kMapViewWidth,  0.8 * kMapViewWidth, kMapViewWidth / 2.0,
          kMapViewHeight / 2.0, kMapViewWidth,       kMapViewHeight};
}

// Recorded intrinsics scaled to fit the picture, the image centred in it.
Intrinsics fit_to_picture(const Intrinsics& k) {
  const double s = std::min(static_cast<double>(kMapViewWidth) / k.width,
                            static_cast<double>(kMapViewHeight) / k.height);
  return {k.fx * s,
          k.fy * s,
          k.cx * s + (kMapViewWidth - k.width * s) / 2,
          k.cy * s + (kMapViewHeight - k.height * s) / 2,
          kMapViewWidth,
          kMapViewHeight};
}

// Segment a-b (world) drawn with `cam`: cut at the near plane, then at a margin around the
// picture (so a point just in front of the camera does not make a line millions of pixels long).
void draw_segment(splat::Image8& out, const splat::Camera& cam, const Eigen::Vector3d& a_world,
                  const Eigen::Vector3d& b_world, const uint8_t rgb[3]) {
  Eigen::Vector3d a = cam.T_cam_world * a_world, b = cam.T_cam_world * b_world;
  if (a.z() < cam.near && b.z() < cam.near) return;
  if (a.z() < cam.near) a = a + (b - a) * ((cam.near - a.z()) / (b.z() - a.z()));
  if (b.z() < cam.near) b = b + (a - b) * ((cam.near - b.z()) / (a.z() - b.z()));
  const auto px = [&](const Eigen::Vector3d& p) {
    return Eigen::Vector2d(cam.fx * p.x() / p.z() + cam.cx, cam.fy * p.y() / p.z() + cam.cy);
  };
  const Eigen::Vector2d p0 = px(a), d = px(b) - p0;
  // Liang-Barsky clipping to the picture and a 2-pixel margin.
  double t0 = 0, t1 = 1;
  const double lo[2] = {-2.0, -2.0}, hi[2] = {out.width + 2.0, out.height + 2.0};
  for (int axis = 0; axis < 2; ++axis) {
    for (const double edge : {lo[axis], hi[axis]}) {
      const bool low = edge == lo[axis];
      const double q = low ? p0[axis] - edge : edge - p0[axis], p = low ? -d[axis] : d[axis];
      if (p == 0) {
        if (q < 0) return;
        continue;
      }
      const double r = q / p;
      if (p < 0)
        t0 = std::max(t0, r);
      else
        t1 = std::min(t1, r);
    }
  }
  if (t0 > t1) return;
  draw_line(out, PixelRect{0, 0, out.width, out.height}, p0 + t0 * d, p0 + t1 * d, rgb);
}

// A camera as a pyramid: its centre joined to its image corners at `depth` metres.
void draw_frustum(splat::Image8& out, const splat::Camera& cam,
                  const Eigen::Isometry3d& T_world_cam, const Intrinsics& k, double depth,
                  const uint8_t rgb[3]) {
  const double u[4] = {0, 1.0 * k.width, 1.0 * k.width, 0},
               v[4] = {0, 0, 1.0 * k.height, 1.0 * k.height};
  Eigen::Vector3d corner[4];
  for (int c = 0; c < 4; ++c) {
    corner[c] = T_world_cam *
                Eigen::Vector3d((u[c] - k.cx) / k.fx * depth, (v[c] - k.cy) / k.fy * depth, depth);
  }
  for (int c = 0; c < 4; ++c) {
    draw_segment(out, cam, T_world_cam.translation(), corner[c], rgb);
    draw_segment(out, cam, corner[c], corner[(c + 1) % 4], rgb);
  }
}

double distance_to_pivot(const MapViewCamera& view) {
  return (view.pivot - view.T_world_view.translation()).norm();
}

// The radius about the map's centre that holds the map and every camera.
double scene_radius(const MapScene& scene) {
  double radius = scene.extent.radius;
  for (const auto& T : scene.cameras)
    radius = std::max(radius, (T.translation() - scene.extent.center).norm());
  return radius;
}

}  // namespace

MapScene make_map_scene(splat::Gaussians map, std::vector<Eigen::Isometry3d> cameras,
                        std::vector<double> timestamps, std::optional<Intrinsics> intrinsics,
                        const Eigen::Vector3d& up) {
  if (map.empty()) throw splat::Error("view: the map has no Gaussians");
  if (!up.allFinite() || !(up.norm() > 0))
    throw splat::Error("view: the up vector is zero or not finite");
  if (!timestamps.empty() && timestamps.size() != cameras.size()) {
    throw splat::Error("view: " + std::to_string(timestamps.size()) + " timestamps for " +
                       std::to_string(cameras.size()) + " cameras");
  }
  MapScene scene;
  scene.extent = map_extent(map);
  scene.map = std::move(map);
  scene.cameras = std::move(cameras);
  scene.timestamps = std::move(timestamps);
  scene.intrinsics = intrinsics;
  scene.up = up.normalized();
  return scene;
}

MapViewCamera overview_view(const MapScene& scene) {
  const Eigen::Vector3d& up = scene.up;
  const Eigen::Vector3d center = scene.extent.center;
  const double radius = scene_radius(scene);
  Eigen::Vector3d heading = Eigen::Vector3d::Zero();
  for (const auto& T : scene.cameras) heading += T.linear().col(2);
  heading -= heading.dot(up) * up;
  heading = heading.norm() > 1e-6 ? heading.normalized() : Eigen::Vector3d(-up.unitOrthogonal());
  const double distance = 2.5 * radius, elevation = 25.0 * M_PI / 180.0;
  const Eigen::Vector3d eye =
      center + distance * (-std::cos(elevation) * heading + std::sin(elevation) * up);
  MapViewCamera view;
  view.T_world_view = look_at(eye, center, up);
  view.pivot = center;
  view.k = default_intrinsics();
  return view;
}

MapViewCamera recorded_view(const MapScene& scene, int i) {
  const int n = static_cast<int>(scene.cameras.size());
  if (i < 0 || i >= n) {
    throw splat::Error("view: camera " + std::to_string(i) + " is not recorded" +
                       (n == 0 ? std::string(": the map has no cameras")
                               : ", expected 0 to " + std::to_string(n - 1)));
  }
  MapViewCamera view;
  view.T_world_view = scene.cameras[static_cast<std::size_t>(i)];
  view.k = scene.intrinsics ? fit_to_picture(*scene.intrinsics) : default_intrinsics();
  const Eigen::Vector3d eye = view.T_world_view.translation(),
                        axis = view.T_world_view.linear().col(2);
  const double r = scene.extent.radius;
  view.pivot = eye + std::clamp((scene.extent.center - eye).dot(axis), 0.1 * r, 3 * r) * axis;
  view.camera = i;
  return view;
}

void orbit_view(MapViewCamera& view, const MapScene& scene, double dx_px, double dy_px) {
  const Eigen::Vector3d& up = scene.up;
  const Eigen::Vector3d a = up.unitOrthogonal(), b = up.cross(a);
  const Eigen::Vector3d offset = view.T_world_view.translation() - view.pivot;
  const double d = offset.norm();
  double elevation = std::asin(std::clamp(offset.dot(up) / d, -1.0, 1.0));
  double azimuth = std::atan2(offset.dot(b), offset.dot(a));
  // Dragging right turns the scene right: the view goes left about the pivot; dragging down
  // tips the scene's top towards the view: the view rises.
  azimuth -= kOrbitRadiansPerPixel * dx_px;
  elevation = std::clamp(elevation + kOrbitRadiansPerPixel * dy_px, -kMaxElevation, kMaxElevation);
  const Eigen::Vector3d eye =
      view.pivot + d * (std::cos(elevation) * (std::cos(azimuth) * a + std::sin(azimuth) * b) +
                        std::sin(elevation) * up);
  view.T_world_view = look_at(eye, view.pivot, up);
  view.camera = -1;
}

void pan_view(MapViewCamera& view, double dx_px, double dy_px) {
  // A pixel at the pivot's depth d spans d / f metres; the scene follows the mouse.
  const double d = distance_to_pivot(view);
  const Eigen::Vector3d shift = -(view.T_world_view.linear().col(0) * (dx_px * d / view.k.fx) +
                                  view.T_world_view.linear().col(1) * (dy_px * d / view.k.fy));
  view.T_world_view.translation() += shift;
  view.pivot += shift;
  view.camera = -1;
}

void zoom_view(MapViewCamera& view, const MapScene& scene, double steps) {
  const double r = scene.extent.radius;
  const double d =
      std::clamp(distance_to_pivot(view) * std::pow(kZoomPerStep, steps), 1e-3 * r, 100 * r);
  view.T_world_view.translation() = view.pivot - d * view.T_world_view.linear().col(2);
  view.camera = -1;
}

void fly_view(MapViewCamera& view, const MapScene& scene, const Eigen::Vector3d& right_up_forward) {
  const Eigen::Vector3d shift = view.T_world_view.linear().col(0) * right_up_forward.x() +
                                scene.up * right_up_forward.y() +
                                view.T_world_view.linear().col(2) * right_up_forward.z();
  view.T_world_view.translation() += shift;
  view.pivot += shift;
  view.camera = -1;
}

splat::Camera render_camera(const MapViewCamera& view, const MapScene& scene, int downsample) {
  const double s = std::max(1, downsample);
  const Intrinsics k{view.k.fx / s,
                     view.k.fy / s,
                     view.k.cx / s,
                     view.k.cy / s,
                     std::max(1, view.k.width / std::max(1, downsample)),
                     std::max(1, view.k.height / std::max(1, downsample))};
  splat::Camera cam = make_camera(k, view.T_world_view);
  cam.near = std::max(1e-4, 0.005 * scene.extent.radius);
  return cam;
}

splat::Image8 compose_map_view(const MapScene& scene, const MapViewCamera& view,
                               splat::Rasterizer& rasterizer, int downsample) {
  downsample = std::max(1, downsample);
  splat::Image8 out(kMapViewWidth, kMapViewHeight, 3, 24);
  const splat::Camera low = render_camera(view, scene, downsample);
  splat::RenderSettings settings;
  settings.background = {0.1f, 0.1f, 0.1f};
  const splat::ForwardResult f = rasterizer.forward(scene.map, low, settings);
  for (int y = 0; y < kMapViewHeight; ++y) {
    const int sy = std::min(y / downsample, low.height - 1);
    for (int x = 0; x < kMapViewWidth; ++x) {
      const std::size_t o =
          (static_cast<std::size_t>(sy) * low.width + std::min(x / downsample, low.width - 1)) * 3;
      for (int c = 0; c < 3; ++c) {
        out.at(x, y, c) = static_cast<uint8_t>(std::clamp(f.rgb[o + c], 0.f, 1.f) * 255.f + 0.5f);
      }
    }
  }
  // Cameras and trajectory, drawn at the picture's full resolution.
  const splat::Camera cam = render_camera(view, scene, 1);
  const std::size_t n = scene.cameras.size();
  for (std::size_t i = 1; i < n; ++i) {
    draw_segment(out, cam, scene.cameras[i - 1].translation(), scene.cameras[i].translation(),
                 kTrajectoryRgb);
  }
  const Intrinsics k = scene.intrinsics.value_or(default_intrinsics());
  const double depth = kFrustumDepth * scene_radius(scene);
  const std::size_t step =
      std::max<std::size_t>(1, (n + kMaxCameraMarkers - 1) / kMaxCameraMarkers);
  const auto marker = [&](std::size_t i) {
    // A frustum about the eye would cover the picture with its lines (the cameras beside the
    // one shown, a few centimetres apart).
    const double distance =
        (scene.cameras[i].translation() - view.T_world_view.translation()).norm();
    if (static_cast<int>(i) == view.camera || distance < kMarkerClearance * depth) return;
    draw_frustum(out, cam, scene.cameras[i], k, depth, kCameraMarkerRgb);
  };
  for (std::size_t i = 0; i < n; i += step) marker(i);
  if (n > 1 && (n - 1) % step != 0) marker(n - 1);  // the last, always
  return out;
}

}  // namespace app
