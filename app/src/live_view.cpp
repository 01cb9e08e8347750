#include "app/live_view.h"

#include <algorithm>
#include <cmath>

#include "app/views.h"

namespace app {
namespace {

constexpr int kRenderWidth = kMapPanelWidth / 2, kRenderHeight = kLiveViewHeight / 2;

splat::Camera view_camera(const LiveViewState& state, const ViewCamera& view) {
  Intrinsics k{0.6 * kRenderWidth, 0.6 * kRenderWidth, kRenderWidth / 2.0, kRenderHeight / 2.0, kRenderWidth,
               kRenderHeight};
  if (view.follow || !state.map || state.map->empty()) {
    // Half a metre behind and 0.2 m above the current camera (OpenCV axes: y down, z forward).
    Eigen::Isometry3d T_world_view = state.T_world_cam * Eigen::Translation3d(0, -0.2, -0.5);
    splat::Camera cam = make_camera(k, T_world_view);
    cam.near = 0.05;
    return cam;
  }
  const MapExtent extent = map_extent(*state.map);
  // World "up" is the first camera's -y (the world frame is the first camera's).
  const Eigen::Vector3d up(0, -1, 0);
  const Eigen::Vector3d dir(std::cos(view.pitch) * std::sin(view.yaw), -std::sin(view.pitch),
                            -std::cos(view.pitch) * std::cos(view.yaw));
  const Eigen::Vector3d eye = extent.center + 2.5 * extent.radius * view.zoom * dir;
  splat::Camera cam = make_camera(k, look_at(eye, extent.center, up));
  cam.near = std::max(1e-3, 0.01 * extent.radius);
  return cam;
}

void put(splat::Image8& image, int x, int y, const uint8_t rgb[3]) {
  if (x < 0 || y < 0 || x >= kMapPanelWidth || y >= image.height) return;
  for (int c = 0; c < 3; ++c) image.at(x, y, c) = rgb[c];
}

// Line of width 2 between two panel pixels.
void line(splat::Image8& image, Eigen::Vector2d a, Eigen::Vector2d b, const uint8_t rgb[3]) {
  const int steps = static_cast<int>(std::ceil((b - a).cwiseAbs().maxCoeff())) + 1;
  for (int s = 0; s <= steps; ++s) {
    const Eigen::Vector2d p = a + (b - a) * (static_cast<double>(s) / steps);
    const int x = static_cast<int>(std::floor(p.x())), y = static_cast<int>(std::floor(p.y()));
    put(image, x, y, rgb);
    put(image, x + 1, y, rgb);
    put(image, x, y + 1, rgb);
  }
}

}  // namespace

splat::Image8 compose_live_view(const LiveViewState& state, const ViewCamera& view, splat::Rasterizer& rasterizer) {
  splat::Image8 out(kLiveViewWidth, kLiveViewHeight, 3, 24);
  const splat::Camera cam = view_camera(state, view);
  if (state.map && !state.map->empty()) {
    splat::RenderSettings settings;
    settings.background = {0.1f, 0.1f, 0.1f};
    const splat::ForwardResult f = rasterizer.forward(*state.map, cam, settings);
    for (int y = 0; y < kLiveViewHeight; ++y) {
      for (int x = 0; x < kMapPanelWidth; ++x) {
        const std::size_t o = (static_cast<std::size_t>(y / 2) * kRenderWidth + x / 2) * 3;
        for (int c = 0; c < 3; ++c) {
          out.at(x, y, c) = static_cast<uint8_t>(std::clamp(f.rgb[o + c], 0.f, 1.f) * 255.f + 0.5f);
        }
      }
    }
  }
  // Trajectory and current camera, projected with the view camera (panel pixels = 2x render).
  auto project = [&](const Eigen::Vector3d& p_world, Eigen::Vector2d& px) {
    const Eigen::Vector3d p = cam.T_cam_world * p_world;
    if (p.z() < cam.near) return false;
    px = 2.0 * Eigen::Vector2d(cam.fx * p.x() / p.z() + cam.cx, cam.fy * p.y() / p.z() + cam.cy);
    return true;
  };
  for (std::size_t i = 1; i < state.trajectory.size(); ++i) {
    Eigen::Vector2d a, b;
    if (project(state.trajectory[i - 1], a) && project(state.trajectory[i], b)) line(out, a, b, kTrajectoryRgb);
  }
  Eigen::Vector2d here;
  if (project(state.T_world_cam.translation(), here)) {
    for (int dy = -4; dy <= 4; ++dy) {
      for (int dx = -4; dx <= 4; ++dx) put(out, static_cast<int>(here.x()) + dx, static_cast<int>(here.y()) + dy, kCameraRgb);
    }
  }
  // The input frame, scaled (nearest) into the 320x240 top-right panel.
  const splat::Image8& in = state.input;
  const int panel_w = kLiveViewWidth - kMapPanelWidth, panel_h = kLiveViewHeight / 2;
  if (in.width > 0 && in.height > 0 && in.channels == 3) {
    for (int y = 0; y < panel_h; ++y) {
      for (int x = 0; x < panel_w; ++x) {
        const int sx = x * in.width / panel_w, sy = y * in.height / panel_h;
        for (int c = 0; c < 3; ++c) out.at(kMapPanelWidth + x, y, c) = in.at(sx, sy, c);
      }
    }
  }
  return out;
}

}  // namespace app
