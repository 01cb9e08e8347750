#include "commands/render_command.h"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "io/image_io.h"
#include "io/map_io.h"
#include "commands/progress.h"
#include "io/trajectory.h"
#include "viewer/views.h"
#include "splat/error.h"

namespace app {
namespace {

Eigen::Vector3d parse_vector3(const std::string& text, const std::string& what) {
  std::stringstream ss(text);
  Eigen::Vector3d v;
  int count = 0;
  for (std::string item; std::getline(ss, item, ',');) {
    char* end = nullptr;
    const double x = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !std::isfinite(x) || count >= 3) {
      throw splat::Error(what + " '" + text + "': expected three comma-separated numbers");
    }
    v[count++] = x;
  }
  if (count != 3) throw splat::Error(what + " '" + text + "': expected three comma-separated numbers");
  return v;
}

struct Formats {
  bool png = false, exr = false;
};

Formats parse_formats(const std::string& text) {
  Formats f;
  std::stringstream ss(text);
  for (std::string item; std::getline(ss, item, ',');) {
    if (item == "png") f.png = true;
    else if (item == "exr") f.exr = true;
    else throw splat::Error("format '" + item + "': expected png, exr or png,exr");
  }
  if (!f.png && !f.exr) throw splat::Error("format '" + text + "': expected png, exr or png,exr");
  return f;
}

}  // namespace

int run_render(const RenderOptions& o) {
  const Formats formats = parse_formats(o.formats);
  splat::RenderSettings settings;
  const Eigen::Vector3d bg = parse_vector3(o.background, "background");
  for (int c = 0; c < 3; ++c) settings.background[static_cast<std::size_t>(c)] = static_cast<float>(bg[c]);

  LoadedMap map = load_map(o.map);
  for (const auto& notice : map.notices) std::fprintf(stderr, "notice: %s\n", notice.c_str());

  std::vector<splat::Camera> cameras;
  if (!o.trajectory.empty()) {
    if (o.intrinsics.empty()) throw splat::Error("render: --trajectory needs --intrinsics fx,fy,cx,cy,W,H");
    const Intrinsics k = parse_intrinsics(o.intrinsics);
    for (const auto& pose : read_tum_trajectory(o.trajectory)) cameras.push_back(make_camera(k, pose.T_world_cam));
    if (cameras.empty()) throw splat::Error(o.trajectory.string() + ": the trajectory has no poses");
  } else {
    const auto [w, h] = parse_size(o.size);
    cameras = orbit_cameras(map_extent(map.gaussians), o.orbit, w, h, parse_vector3(o.up, "up"));
  }

  std::string note;
  auto rasterizer = make_rasterizer(o.backend, note);
  std::fprintf(stderr, "%s\n", note.c_str());
  std::filesystem::create_directories(o.out);

  Progress progress("render", cameras.size(), "views");
  double render_seconds = 0;
  for (std::size_t i = 0; i < cameras.size(); ++i) {
    const auto start = std::chrono::steady_clock::now();
    const splat::ForwardResult frame = rasterizer->forward(map.gaussians, cameras[i], settings);
    render_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    char name[32];
    std::snprintf(name, sizeof(name), "view_%04zu", i);
    if (formats.png) write_png_rgb(o.out / (std::string(name) + ".png"), frame.width, frame.height, frame.rgb);
    if (formats.exr) {
      write_render_exr(o.out / (std::string(name) + ".exr"), frame.width, frame.height, frame.rgb, frame.alpha,
                       frame.depth_normalized, settings.background);
    }
    progress.update(i + 1);
  }
  progress.finish();
  const splat::Camera& c0 = cameras.front();
  std::printf("rendered %zu views of %zu Gaussians at %dx%d with %s: %.1f ms per view -> %s\n", cameras.size(),
              map.gaussians.size(), c0.width, c0.height, rasterizer->name().c_str(),
              1000.0 * render_seconds / static_cast<double>(cameras.size()), o.out.c_str());
  return 0;
}

}  // namespace app
