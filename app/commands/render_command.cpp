#include "commands/render_command.h"

#include <algorithm>
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
#include "commands/label_maps.h"
#include "commands/map_up.h"
#include "commands/progress.h"
#include "commands/run_input.h"
#include "io/trajectory.h"
#include "mapping/gaussian_adam.h"
#include "mapping/label_fusion.h"
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
  std::filesystem::path trajectory;
  std::vector<Eigen::Isometry3d> poses;
  std::optional<Intrinsics> camera;
};

Scene scene_of(const RenderOptions& o) {
  Scene scene{o.map, {}, {}, std::nullopt};
  std::filesystem::path trajectory = o.trajectory;
  if (std::filesystem::is_directory(o.map)) {  // a run folder
    scene.map = o.map / "map.ply";
    if (trajectory.empty()) trajectory = o.map / "trajectory.txt";
    if (o.intrinsics.empty()) {
      const std::filesystem::path summary_path = o.map / "summary.json";
      scene.camera = recorded_camera(summary_path);
      if (!scene.camera) {
        throw splat::Error(summary_path.string() + ": records no camera (\"input\".intrinsics); give --intrinsics fx,fy,cx,cy,W,H");
      }
    }
  }
  if (!o.intrinsics.empty()) scene.camera = parse_intrinsics(o.intrinsics);
  if (!trajectory.empty()) {
    if (!scene.camera) throw splat::Error("render: --trajectory needs --intrinsics fx,fy,cx,cy,W,H");
    for (const auto& pose : read_tum_trajectory(trajectory)) scene.poses.push_back(pose.T_world_cam);
    if (scene.poses.empty()) throw splat::Error(trajectory.string() + ": the trajectory has no poses");
    scene.trajectory = trajectory;
  }
  return scene;
}

// The cameras to render, and a line saying which path they follow.
struct Views {
  std::vector<splat::Camera> cameras;
  std::string description;
};

Views views_of(const RenderOptions& o, const Scene& scene, const splat::Gaussians& map) {
  Views v;
  if (o.orbit || scene.poses.empty()) {
    const int n = o.orbit.value_or(36);
    v.description = "orbit: " + std::to_string(n) + " views about the map";
    const MapUp up = choose_map_up(o.up ? std::optional(parse_vector3(*o.up, "up")) : std::nullopt, scene.map, scene.poses, map);
    if (!scene.poses.empty() && !o.up) {
      v.cameras = orbit_at_camera_height(map_extent(map), scene.poses, n, *scene.camera, up.up);
      v.description += " at the cameras' height";
    } else {
      const auto [w, h] = scene.camera ? std::pair{scene.camera->width, scene.camera->height} : parse_size(o.size);
      v.cameras = orbit_cameras(map_extent(map), n, w, h, up.up);
    }
    char line[96];
    std::snprintf(line, sizeof(line), "\norbit up: %.3f,%.3f,%.3f (", up.up.x(), up.up.y(), up.up.z());
    v.description += line + up.source + ")";
    return v;
  }
  // A trajectory the user names is the path to render; a run's own cameras get a novel path.
  const std::string path = !o.path.empty() ? o.path : o.trajectory.empty() ? "novel" : "recorded";
  const std::string poses = std::to_string(scene.poses.size()) + " poses of " + scene.trajectory.string();
  if (path == "recorded") {
    for (const auto& T : scene.poses) v.cameras.push_back(make_camera(*scene.camera, T));
    v.description = "path: recorded, at the " + poses;
  } else if (path == "novel") {
    const int views = o.views > 0 ? o.views : static_cast<int>(std::min<std::size_t>(scene.poses.size(), kMaxOrbitViews));
    for (const auto& T : novel_path(scene.poses, views, parse_vector3(o.offset, "offset"))) {
      v.cameras.push_back(make_camera(*scene.camera, T));
    }
    v.description = "path: novel, " + std::to_string(views) + " views near the " + poses + ", offset " + o.offset +
                    " m (--path recorded renders at the poses)";
  } else {
    throw splat::Error("path '" + o.path + "': expected novel or recorded");
  }
  return v;
}

// The files an earlier render left in `out` (its views and video).
std::vector<std::filesystem::path> earlier_render_files(const std::filesystem::path& out) {
  std::vector<std::filesystem::path> files;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(out, ec)) {
    const std::string name = entry.path().filename().string();
    const std::string ext = entry.path().extension().string();
    if (name == "render.mp4" || (name.rfind("view_", 0) == 0 && (ext == ".png" || ext == ".exr"))) {
      files.push_back(entry.path());
    }
  }
  return files;
}

// An `out` folder holds one render: an earlier one's views are refused unless `overwrite`.
void refuse_earlier_render(const std::filesystem::path& out, bool overwrite) {
  const std::vector<std::filesystem::path> earlier = earlier_render_files(out);
  if (!earlier.empty() && !overwrite) {
    throw splat::Error(out.string() + ": holds " + std::to_string(earlier.size()) +
                       " files of an earlier render (view_NNNN, render.mp4); give --overwrite to replace them, or "
                       "another --out");
  }
}

// The class ids `only` (the value of `option`, --only or --highlight) names: ids, or names the
// run's summary.json lists ("labels"."ids").
std::vector<uint16_t> wanted_classes(const std::string& option, const std::string& only,
                                     const std::filesystem::path& map_argument) {
  nlohmann::json ids = nlohmann::json::object();
  const std::filesystem::path summary = map_argument / "summary.json";
  if (std::filesystem::is_directory(map_argument) && std::filesystem::exists(summary)) {
    std::ifstream in(summary);
    const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
    if (j.is_object() && j.contains("labels") && j["labels"].contains("ids")) ids = j["labels"]["ids"];
  }
  std::vector<uint16_t> wanted;
  std::stringstream ss(only);
  for (std::string item; std::getline(ss, item, ',');) {
    char* end = nullptr;
    const long id = std::strtol(item.c_str(), &end, 10);
    if (!item.empty() && *end == '\0' && id >= 1 && id <= 65535) {
      wanted.push_back(static_cast<uint16_t>(id));
    } else if (ids.contains(item) && ids[item].is_number_unsigned()) {
      wanted.push_back(ids[item].get<uint16_t>());
    } else {
      std::string known;
      for (const auto& [name, value] : ids.items()) known += (known.empty() ? "" : ", ") + name;
      throw splat::Error(option + ": unknown class '" + item + "' (" +
                         (known.empty() ? std::string("give class ids, or a run folder whose summary.json names them")
                                        : "the run's classes: " + known) +
                         ")");
    }
  }
  if (wanted.empty()) throw splat::Error(option + " '" + only + "': expected comma-separated class names or ids");
  return wanted;
}

// Keeps the Gaussians whose most probable class is one of `wanted` (and their labels).
void keep_classes(LoadedMap& map, const std::vector<uint16_t>& wanted) {
  std::vector<uint8_t> keep(map.gaussians.size());
  for (std::size_t i = 0; i < keep.size(); ++i) {
    keep[i] = std::find(wanted.begin(), wanted.end(), map.labels.best(i)) != wanted.end();
  }
  const auto top = static_cast<std::size_t>(map.labels.top);
  std::size_t out = 0;
  for (std::size_t i = 0; i < keep.size(); ++i) {
    if (!keep[i]) continue;
    for (std::size_t k = 0; k < top; ++k) {
      map.labels.ids[out * top + k] = map.labels.ids[i * top + k];
      map.labels.probabilities[out * top + k] = map.labels.probabilities[i * top + k];
    }
    ++out;
  }
  map.labels.ids.resize(out * top);
  map.labels.probabilities.resize(out * top);
  mapping::remove_gaussians(map.gaussians, keep);
}

// Turns the Gaussians of the other classes grey and dark (their luminance, a third of it over a
// dim floor), so that the wanted ones stand out in their own colours.
void highlight_classes(LoadedMap& map, const std::vector<uint16_t>& wanted) {
  constexpr float kShC0 = 0.28209479177387814f;  // the SH DC basis: colour = kShC0 * dc + 0.5
  splat::Gaussians& g = map.gaussians;
  const std::size_t stride = g.sh.size() / std::max<std::size_t>(1, g.size());
  for (std::size_t i = 0; i < g.size(); ++i) {
    if (std::find(wanted.begin(), wanted.end(), map.labels.best(i)) != wanted.end()) continue;
    float* sh = g.sh.data() + i * stride;
    float rgb[3];
    for (int c = 0; c < 3; ++c) rgb[c] = std::clamp(kShC0 * sh[c] + 0.5f, 0.f, 1.f);
    const float grey = 0.1f + 0.3f * (0.299f * rgb[0] + 0.587f * rgb[1] + 0.114f * rgb[2]);
    for (int c = 0; c < 3; ++c) sh[c] = (grey - 0.5f) / kShC0;
    std::fill(sh + 3, sh + stride, 0.f);  // no view-dependent colour either
  }
}

}  // namespace

int run_render(const RenderOptions& o) {
  const Formats formats = parse_formats(o.formats);
  refuse_earlier_render(o.out, o.overwrite);
  if (formats.mp4) Mp4Writer::require_encoder(o.out / "render.mp4");
  splat::RenderSettings settings;
  const Eigen::Vector3d bg = parse_vector3(o.background, "background");
  for (int c = 0; c < 3; ++c) settings.background[static_cast<std::size_t>(c)] = static_cast<float>(bg[c]);

  const Scene scene = scene_of(o);
  LoadedMap map = load_map(scene.map);
  for (const auto& notice : map.notices) std::fprintf(stderr, "notice: %s\n", notice.c_str());
  if ((o.labels || !o.only.empty() || !o.highlight.empty()) && map.labels.empty()) {
    throw splat::Error(scene.map.string() + ": the map has no classes (--labels, --only, --highlight): reconstruct a "
                       "sequence with label images to make one");
  }
  if (!o.highlight.empty()) highlight_classes(map, wanted_classes("--highlight", o.highlight, o.map));
  if (!o.only.empty()) {
    keep_classes(map, wanted_classes("--only", o.only, o.map));
    if (map.gaussians.empty()) throw splat::Error("--only " + o.only + ": no Gaussian of the map is of these classes");
    std::fprintf(stderr, "--only %s: %zu Gaussians kept\n", o.only.c_str(), map.gaussians.size());
  }
  const Views views = views_of(o, scene, map.gaussians);
  const std::vector<splat::Camera>& cameras = views.cameras;
  std::fprintf(stderr, "%s\n", views.description.c_str());

  std::string note;
  auto rasterizer = make_rasterizer(o.backend, note);
  std::fprintf(stderr, "%s\n", note.c_str());
  for (const auto& file : earlier_render_files(o.out)) std::filesystem::remove(file);  // --overwrite
  std::filesystem::create_directories(o.out);

  double render_seconds = 0;
  const auto render_all = [&](Mp4Writer* video) {
    Progress progress("render", cameras.size(), "views");
    for (std::size_t i = 0; i < cameras.size(); ++i) {
      const auto start = std::chrono::steady_clock::now();
      splat::ForwardResult frame = rasterizer->forward(map.gaussians, cameras[i], settings);
      if (o.labels) {  // the classes instead of the colours, in the palette
        const std::vector<uint8_t> colours =
            label_colours(mapping::render_labels(*rasterizer, map.gaussians, map.labels, cameras[i]));
        for (std::size_t k = 0; k < colours.size(); ++k) frame.rgb[k] = static_cast<float>(colours[k]) / 255.f;
      }
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
