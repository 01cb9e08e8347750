#include "viewer/live_view.h"

#include <algorithm>
#include <cmath>

#include "viewer/views.h"

namespace app {
namespace {

constexpr int kRenderWidth = kMapPanelWidth / 2, kRenderHeight = kLiveViewHeight / 2;

splat::Camera view_camera(const LiveViewState& state, const ViewCamera& view) {
  Intrinsics k{0.6 * kRenderWidth,  0.6 * kRenderWidth, kRenderWidth / 2.0,
               kRenderHeight / 2.0, kRenderWidth,       kRenderHeight};
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

constexpr PixelRect kMapPanel{0, 0, kMapPanelWidth, kLiveViewHeight};
constexpr PixelRect kTopPanel{kMapPanelWidth, kLiveViewHeight / 2, kLiveViewWidth, kLiveViewHeight};

void put(splat::Image8& image, const PixelRect& clip, int x, int y, const uint8_t rgb[3]) {
  if (x < clip.x0 || y < clip.y0 || x >= clip.x1 || y >= clip.y1) return;
  for (int c = 0; c < 3; ++c) image.at(x, y, c) = rgb[c];
}

// Top view of the trajectory (world x right, z up the panel), fitted into the panel.
void draw_top_view(splat::Image8& image, const LiveViewState& state) {
  if (state.trajectory.empty()) return;
  Eigen::Vector2d lo(INFINITY, INFINITY), hi(-INFINITY, -INFINITY);
  for (const auto& p : state.trajectory) {
    lo = lo.cwiseMin(Eigen::Vector2d(p.x(), p.z()));
    hi = hi.cwiseMax(Eigen::Vector2d(p.x(), p.z()));
  }
  const PixelRect& panel = kTopPanel;
  const double margin = 16, span = std::max({hi.x() - lo.x(), hi.y() - lo.y(), 0.1});
  const double scale = (std::min(panel.x1 - panel.x0, panel.y1 - panel.y0) - 2 * margin) / span;
  const Eigen::Vector2d mid = (lo + hi) / 2;
  const Eigen::Vector2d centre((panel.x0 + panel.x1) / 2.0, (panel.y0 + panel.y1) / 2.0);
  auto to_px = [&](const Eigen::Vector3d& p) {
    return Eigen::Vector2d(centre.x() + (p.x() - mid.x()) * scale,
                           centre.y() - (p.z() - mid.y()) * scale);
  };
  for (std::size_t i = 1; i < state.trajectory.size(); ++i) {
    draw_line(image, panel, to_px(state.trajectory[i - 1]), to_px(state.trajectory[i]), kTrajectoryRgb);
  }
  draw_square(image, panel, to_px(state.T_world_cam.translation()), 3, kCameraRgb);
}

}  // namespace

void draw_line(splat::Image8& image, const PixelRect& clip, Eigen::Vector2d a, Eigen::Vector2d b,
               const uint8_t rgb[3]) {
  const int steps = static_cast<int>(std::ceil((b - a).cwiseAbs().maxCoeff())) + 1;
  for (int s = 0; s <= steps; ++s) {
    const Eigen::Vector2d p = a + (b - a) * (static_cast<double>(s) / steps);
    const int x = static_cast<int>(std::floor(p.x())), y = static_cast<int>(std::floor(p.y()));
    put(image, clip, x, y, rgb);
    put(image, clip, x + 1, y, rgb);
    put(image, clip, x, y + 1, rgb);
  }
}

void draw_square(splat::Image8& image, const PixelRect& clip, Eigen::Vector2d centre, int half,
                 const uint8_t rgb[3]) {
  for (int dy = -half; dy <= half; ++dy) {
    for (int dx = -half; dx <= half; ++dx) {
      put(image, clip, static_cast<int>(centre.x()) + dx, static_cast<int>(centre.y()) + dy, rgb);
    }
  }
}

splat::Image8 compose_live_view(const LiveViewState& state, const ViewCamera& view,
                                splat::Rasterizer& rasterizer) {
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
    if (project(state.trajectory[i - 1], a) && project(state.trajectory[i], b)) {
      draw_line(out, kMapPanel, a, b, kTrajectoryRgb);
    }
  }
  Eigen::Vector2d here;
  if (project(state.T_world_cam.translation(), here)) draw_square(out, kMapPanel, here, 4, kCameraRgb);
  draw_top_view(out, state);
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
