#include "commands/view_command.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>

#include "commands/map_up.h"
#include "commands/run_input.h"
#include "io/image_io.h"
#include "io/map_io.h"
#include "io/trajectory.h"
#include "splat/error.h"
#include "viewer/map_view.h"
#include "viewer/viewer_window.h"
#include "viewer/views.h"

namespace app {
namespace {

using Clock = std::chrono::steady_clock;

// Fly keys move half the map's radius a second, four times that with shift.
constexpr double kFlyRadiiPerSecond = 0.5, kFastFactor = 4;
// The longest time one frame's fly step covers, so that a slow frame does not jump the view.
constexpr double kMaxFlyStepSeconds = 0.1;
// A full-resolution picture slower than this (ms) is drawn at half resolution while the view
// moves, and at full resolution once it stops.
constexpr double kInteractiveMs = 40;
// How long to wait for input when nothing moves (seconds): the window stays responsive to
// closing and the loop costs nothing.
constexpr double kIdleWaitSeconds = 0.1;

struct LoadedScene {
  MapScene scene;
  std::string up_source;  // where the up direction came from, for the start-up line
};

LoadedScene load_scene(const ViewOptions& o) {
  if (!std::filesystem::exists(o.path))
    throw splat::Error(o.path.string() + ": no such file or folder");
  std::filesystem::path map_path = o.path;
  std::vector<Eigen::Isometry3d> cameras;
  std::vector<double> timestamps;
  std::optional<Intrinsics> intrinsics;
  if (std::filesystem::is_directory(o.path)) {  // a run folder
    map_path = o.path / "map.ply";
    if (!std::filesystem::exists(map_path)) {
      throw splat::Error(map_path.string() +
                         ": no such file (expected a gslam run folder, or a .ply/.glb/.gltf map)");
    }
    const std::filesystem::path trajectory = o.path / "trajectory.txt";
    if (std::filesystem::exists(trajectory)) {
      for (const StampedPose& pose : read_tum_trajectory(trajectory)) {
        cameras.push_back(pose.T_world_cam);
        timestamps.push_back(pose.timestamp);
      }
    }
    const std::filesystem::path summary = o.path / "summary.json";
    if (std::filesystem::exists(summary)) intrinsics = recorded_camera(summary);
  }
  LoadedMap map = load_map(map_path);
  for (const auto& notice : map.notices) std::fprintf(stderr, "notice: %s\n", notice.c_str());
  std::optional<Eigen::Vector3d> given;
  if (!o.up.empty()) {
    if (o.up.size() != 3)
      throw splat::Error("--up: expected x,y,z, got " + std::to_string(o.up.size()) + " numbers");
    given = Eigen::Vector3d(o.up[0], o.up[1], o.up[2]);
  }
  const MapUp up = choose_map_up(given, map_path, cameras, map.gaussians);
  return {make_map_scene(std::move(map.gaussians), std::move(cameras), std::move(timestamps),
                         intrinsics, up.up),
          up.source};
}

// The window's title: what is shown and from where.
std::string title_of(const ViewOptions& o, const MapScene& scene, const MapViewCamera& view) {
  std::string title =
      "gslam view: " + o.path.string() + ", " + std::to_string(scene.map.size()) + " Gaussians";
  const std::size_t n = scene.cameras.size();
  if (view.camera >= 0) {
    const std::size_t i = static_cast<std::size_t>(view.camera);
    title += " - camera " + std::to_string(i) + " of " + std::to_string(n);
    if (!scene.timestamps.empty()) {
      char stamp[48];
      std::snprintf(stamp, sizeof(stamp), " (t %.3f s)", scene.timestamps[i]);
      title += stamp;
    }
  } else {
    title += n > 0 ? " - free view (" + std::to_string(n) +
                         " cameras: n/p steps through them, Home: overview)"
                   : " - free view (Home: overview)";
  }
  return title;
}

}  // namespace

int run_view(const ViewOptions& o) {
  const LoadedScene loaded = load_scene(o);
  const MapScene& scene = loaded.scene;
  MapViewCamera view = o.camera ? recorded_view(scene, *o.camera) : overview_view(scene);
  // The window first: without a display, its error is the only line printed.
  ViewerWindow window("gslam view", ViewerControls::kMap, kMapViewWidth, kMapViewHeight);
  std::string note;
  auto rasterizer = make_rasterizer(o.backend, note);
  std::fprintf(stderr, "%s\n", note.c_str());
  std::fprintf(stderr, "view: %zu Gaussians, %zu cameras%s, up %.3f,%.3f,%.3f (%s)\n",
               scene.map.size(), scene.cameras.size(),
               scene.intrinsics ? "" : " (intrinsics unknown)", scene.up.x(), scene.up.y(),
               scene.up.z(), loaded.up_source.c_str());

  const int cameras = static_cast<int>(scene.cameras.size());
  int last_camera = view.camera;  // n/p from a free view go on from the camera shown last
  bool first = true, full_pending = false;
  double full_ms = 0;
  Clock::time_point last = Clock::now();
  while (!window.closed()) {
    window.poll();
    const ViewerInput in = window.take_input();
    const Clock::time_point now = Clock::now();
    const double dt =
        std::min(kMaxFlyStepSeconds, std::chrono::duration<double>(now - last).count());
    last = now;
    if (in.overview) view = overview_view(scene);
    if (in.camera_step != 0 && cameras > 0) {
      const int from = last_camera >= 0 ? last_camera : (in.camera_step > 0 ? -1 : cameras);
      view = recorded_view(scene, ((from + in.camera_step) % cameras + cameras) % cameras);
    }
    if (in.orbit_dx != 0 || in.orbit_dy != 0) orbit_view(view, scene, in.orbit_dx, in.orbit_dy);
    if (in.pan_dx != 0 || in.pan_dy != 0) pan_view(view, in.pan_dx, in.pan_dy);
    if (in.zoom_steps != 0) zoom_view(view, scene, in.zoom_steps);
    if (!in.fly.isZero()) {
      const double metres =
          kFlyRadiiPerSecond * scene.extent.radius * dt * (in.fast ? kFastFactor : 1);
      fly_view(view, scene, in.fly.cast<double>() * metres);
    }
    if (view.camera >= 0) last_camera = view.camera;

    const bool changed = first || in.any();
    if (!changed && !full_pending) {
      window.wait(kIdleWaitSeconds);
      continue;
    }
    const bool quick = changed && !first && full_ms > kInteractiveMs;
    const Clock::time_point start = Clock::now();
    const splat::Image8 picture = compose_map_view(scene, view, *rasterizer, quick ? 2 : 1);
    if (!quick) full_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    full_pending = quick;
    const bool screenshot = first && !o.screenshot.empty();
    splat::Image8 capture;
    window.show(picture, title_of(o, scene, view), screenshot ? &capture : nullptr);
    if (screenshot) {
      write_png_rgb8(o.screenshot, capture);
      std::printf("view: saved %s (%dx%d)\n", o.screenshot.c_str(), capture.width, capture.height);
      return 0;
    }
    first = false;
  }
  return 0;
}

}  // namespace app
