#include "commands/render_command.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <optional>
#include <sstream>

#include <nlohmann/json.hpp>

#include "io/atomic_file.h"
#include "io/image_io.h"
#include "io/video_io.h"
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
  bool png = false, exr = false, mp4 = false;
};

Formats parse_formats(const std::string& text) {
  Formats f;
  std::stringstream ss(text);
  for (std::string item; std::getline(ss, item, ',');) {
    if (item == "png") f.png = true;
    else if (item == "exr") f.exr = true;
    else if (item == "mp4") f.mp4 = true;
    else throw splat::Error("format '" + item + "': expected a comma-separated list of png, exr and mp4");
  }
  if (!f.png && !f.exr && !f.mp4) throw splat::Error("format '" + text + "': expected png, exr and/or mp4");
  return f;
}

// What to render: the map file, and the camera poses and intrinsics where there are any.
struct Scene {
  std::filesystem::path map;
  std::vector<Eigen::Isometry3d> poses;
  std::optional<Intrinsics> camera;
};

Scene scene_of(const RenderOptions& o) {
  Scene scene{o.map, {}, std::nullopt};
  std::filesystem::path trajectory = o.trajectory;
  if (std::filesystem::is_directory(o.map)) {  // a run folder
    scene.map = o.map / "map.ply";
    if (trajectory.empty()) trajectory = o.map / "trajectory.txt";
    if (o.intrinsics.empty()) {
      const std::filesystem::path summary_path = o.map / "summary.json";
      std::ifstream in(summary_path);
      if (!in) throw splat::Error(summary_path.string() + ": cannot open file (not a run folder?)");
      const nlohmann::json summary = nlohmann::json::parse(in, nullptr, false);
      try {
        const nlohmann::json& k = summary.at("input").at("intrinsics");
        scene.camera = Intrinsics{k.at("fx").get<double>(), k.at("fy").get<double>(), k.at("cx").get<double>(),
                                  k.at("cy").get<double>(), k.at("width").get<int>(), k.at("height").get<int>()};
      } catch (const nlohmann::json::exception&) {
        throw splat::Error(summary_path.string() + ": records no camera (\"input\".intrinsics); give --intrinsics fx,fy,cx,cy,W,H");
      }
    }
  }
  if (!o.intrinsics.empty()) scene.camera = parse_intrinsics(o.intrinsics);
  if (!trajectory.empty()) {
    if (!scene.camera) throw splat::Error("render: --trajectory needs --intrinsics fx,fy,cx,cy,W,H");
    for (const auto& pose : read_tum_trajectory(trajectory)) scene.poses.push_back(pose.T_world_cam);
    if (scene.poses.empty()) throw splat::Error(trajectory.string() + ": the trajectory has no poses");
  }
  return scene;
}

std::vector<splat::Camera> views_of(const RenderOptions& o, const Scene& scene, const splat::Gaussians& map) {
  std::vector<splat::Camera> cameras;
  if (o.orbit || scene.poses.empty()) {
    const int n = o.orbit.value_or(36);
    if (!scene.poses.empty() && !o.up) return orbit_at_camera_height(map_extent(map), scene.poses, n, *scene.camera);
    const auto [w, h] = scene.camera ? std::pair{scene.camera->width, scene.camera->height} : parse_size(o.size);
    return orbit_cameras(map_extent(map), n, w, h, parse_vector3(o.up.value_or("0,0,1"), "up"));
  }
  if (o.path == "recorded") {
    for (const auto& T : scene.poses) cameras.push_back(make_camera(*scene.camera, T));
  } else if (o.path == "novel") {
    const int views = o.views > 0 ? o.views : static_cast<int>(std::min<std::size_t>(scene.poses.size(), kMaxOrbitViews));
    for (const auto& T : novel_path(scene.poses, views, parse_vector3(o.offset, "offset"))) {
      cameras.push_back(make_camera(*scene.camera, T));
    }
  } else {
    throw splat::Error("path '" + o.path + "': expected novel or recorded");
  }
  return cameras;
}

}  // namespace

int run_render(const RenderOptions& o) {
  const Formats formats = parse_formats(o.formats);
  splat::RenderSettings settings;
  const Eigen::Vector3d bg = parse_vector3(o.background, "background");
  for (int c = 0; c < 3; ++c) settings.background[static_cast<std::size_t>(c)] = static_cast<float>(bg[c]);

  const Scene scene = scene_of(o);
  LoadedMap map = load_map(scene.map);
  for (const auto& notice : map.notices) std::fprintf(stderr, "notice: %s\n", notice.c_str());
  const std::vector<splat::Camera> cameras = views_of(o, scene, map.gaussians);

  std::string note;
  auto rasterizer = make_rasterizer(o.backend, note);
  std::fprintf(stderr, "%s\n", note.c_str());
  std::filesystem::create_directories(o.out);

  double render_seconds = 0;
  const auto render_all = [&](Mp4Writer* video) {
    Progress progress("render", cameras.size(), "views");
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
      if (video) video->add(frame.rgb);
      progress.update(i + 1);
    }
    progress.finish();
  };
  const splat::Camera& c0 = cameras.front();
  if (formats.mp4) {
    write_atomically(o.out / "render.mp4", [&](const std::filesystem::path& tmp) {
      Mp4Writer video(tmp, c0.width, c0.height, o.fps);
      render_all(&video);
      video.finish();
    });
  } else {
    render_all(nullptr);
  }
  std::printf("rendered %zu views of %zu Gaussians at %dx%d with %s: %.1f ms per view -> %s%s\n", cameras.size(),
              map.gaussians.size(), c0.width, c0.height, rasterizer->name().c_str(),
              1000.0 * render_seconds / static_cast<double>(cameras.size()), o.out.c_str(),
              formats.mp4 ? "/render.mp4" : "");
  return 0;
}

}  // namespace app
