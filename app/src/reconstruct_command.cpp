#include "app/reconstruct_command.h"

#include <chrono>
#include <cstdio>
#include <fstream>

#include <nlohmann/json.hpp>

#include "app/atomic_file.h"
#include "app/evaluation.h"
#include "app/image_io.h"
#include "app/map_io.h"
#include "app/progress.h"
#include "app/slam.h"
#include "app/synthetic_sequence.h"
#include "app/trajectory.h"
#include "splat/error.h"

namespace app {
namespace {

// Peak resident memory of this process in MiB (Linux VmHWM), 0 if unknown.
double peak_memory_mib() {
  std::ifstream status("/proc/self/status");
  std::string key;
  while (status >> key) {
    if (key == "VmHWM:") {
      double kib = 0;
      status >> kib;
      return kib / 1024.0;
    }
    std::getline(status, key);
  }
  return 0;
}

void write_json(const std::filesystem::path& path, const nlohmann::json& j) {
  write_atomically(path, [&](const std::filesystem::path& tmp) {
    std::ofstream out(tmp);
    out << j.dump(2) << "\n";
    if (!out.flush()) throw splat::Error(tmp.string() + ": write failed");
  });
}

// SLAM settings from a JSON file: {"tracking": {...}, "mapping": {...}, "keyframe_every": N}.
SlamConfig load_config(const std::filesystem::path& path) {
  SlamConfig c;
  if (path.empty()) return c;
  std::ifstream in(path);
  if (!in) throw splat::Error(path.string() + ": cannot open file");
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
    auto get = [](const nlohmann::json& obj, const char* key, auto& value) {
      if (obj.contains(key)) value = obj.at(key).get<std::decay_t<decltype(value)>>();
    };
    get(j, "keyframe_every", c.keyframe_every);
    get(j, "keyframe_translation", c.keyframe_translation);
    get(j, "keyframe_rotation_deg", c.keyframe_rotation_deg);
    if (j.contains("tracking")) {
      const auto& t = j.at("tracking");
      get(t, "pyramid", c.tracking.pyramid);
      get(t, "iterations", c.tracking.iterations);
      get(t, "depth_sigma", c.tracking.depth_sigma);
      get(t, "color_sigma", c.tracking.color_sigma);
      get(t, "color_weight", c.tracking.color_weight);
      get(t, "alpha_threshold", c.tracking.alpha_threshold);
    }
    if (j.contains("mapping")) {
      const auto& m = j.at("mapping");
      get(m, "iterations", c.mapping.iterations);
      get(m, "window", c.mapping.window);
      get(m, "resolution_factor", c.mapping.resolution_factor);
      get(m, "seed_stride", c.mapping.seed.stride);
      get(m, "isotropic", c.mapping.isotropic);
    }
  } catch (const nlohmann::json::exception& e) {
    throw splat::Error(path.string() + ": " + e.what());
  }
  c.tracking.validate();
  c.mapping.validate();
  return c;
}

}  // namespace

int run_reconstruct(const ReconstructOptions& o) {
  std::filesystem::create_directories(o.out);
  std::filesystem::path input = o.dataset;
  if (input.empty()) {
    input = o.out / "synthetic_input";
    std::fprintf(stderr, "no dataset given: generating the bundled synthetic sequence into %s\n", input.c_str());
    write_synthetic_sequence(input, SyntheticOptions{});
  }
  const Dataset dataset = open_dataset(input, o.dataset_options);
  const SlamConfig config = load_config(o.config);
  std::fprintf(stderr, "dataset %s (%s): %zu frames at %dx%d%s", input.c_str(), dataset.format.c_str(),
               dataset.entries.size(), dataset.intrinsics.width, dataset.intrinsics.height,
               dataset.has_ground_truth() ? ", with ground truth" : "");
  if (dataset.skipped_missing > 0) std::fprintf(stderr, ", %zu listed files missing (skipped)", dataset.skipped_missing);
  if (dataset.unmatched > 0) std::fprintf(stderr, ", %zu colour frames without depth", dataset.unmatched);
  std::fprintf(stderr, "\n");

  std::string note;
  auto rasterizer = make_rasterizer(o.backend, note);
  std::fprintf(stderr, "%s\n", note.c_str());
  SlamSystem slam(*rasterizer, config);

  std::vector<StampedPose> trajectory;
  std::vector<FrameRecord> records;
  double tracking_ms = 0, mapping_ms = 0, loading_ms = 0;
  std::size_t failures = 0, retries = 0;
  Progress progress("reconstruct", dataset.entries.size(), "frames");
  const auto start = std::chrono::steady_clock::now();

  auto summary = [&](bool complete) {
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const double n = std::max<double>(1, static_cast<double>(records.size()));
    nlohmann::json j = {
        {"complete", complete},
        {"dataset", input.string()},
        {"backend", rasterizer->name()},
        {"frames", records.size()},
        {"keyframes", slam.keyframes_added()},
        {"gaussians", slam.map().size()},
        {"fps", static_cast<double>(records.size()) / std::max(seconds, 1e-9)},
        {"seconds", seconds},
        {"time_per_frame_ms", {{"tracking", tracking_ms / n}, {"mapping", mapping_ms / n}, {"loading", loading_ms / n}}},
        {"tracking_failures", failures},
        {"tracking_retries", retries},
        {"peak_memory_mib", peak_memory_mib()},
        {"device_memory_mib", static_cast<double>(rasterizer->device_memory_bytes()) / (1 << 20)},
    };
    if (complete && dataset.has_ground_truth()) {
      std::vector<StampedPose> truth;
      for (const auto& e : dataset.entries) {
        if (e.T_world_cam_truth) truth.push_back({e.timestamp, *e.T_world_cam_truth});
      }
      const TrajectoryErrors errors = evaluate_trajectory(trajectory, truth);
      j["ate_rmse_m"] = errors.ate_rmse;
      j["ate_matched_frames"] = errors.matched;
    }
    write_json(o.out / "summary.json", j);
  };

  for (std::size_t i = 0; i < dataset.entries.size(); ++i) {
    const auto load_start = std::chrono::steady_clock::now();
    const splat::RgbdFrame frame = dataset.load(i);
    loading_ms += std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - load_start).count();
    const FrameRecord record = slam.process(frame);
    tracking_ms += record.tracking_ms;
    mapping_ms += record.mapping_ms;
    failures += record.tracked ? 0 : 1;
    retries += record.retried ? 1 : 0;
    if (!record.tracked) std::fprintf(stderr, "\nframe %zu: tracking failed (%s)\n", i, record.reason.c_str());
    records.push_back(record);
    trajectory.push_back({record.timestamp, record.T_world_cam});
    progress.update(i + 1, std::to_string(record.gaussians) + " Gaussians, " + std::to_string(slam.keyframes_added()) + " keyframes");
    const std::size_t every = static_cast<std::size_t>(std::max(1, o.checkpoint_every));
    if ((i + 1) % every == 0) {
      write_tum_trajectory(o.out / "trajectory.txt", trajectory);
      summary(false);
    }
    if ((i + 1) % (5 * every) == 0) save_map(o.out / "map.ply", slam.map());
  }
  progress.finish();
  write_tum_trajectory(o.out / "trajectory.txt", trajectory);
  save_map(o.out / "map.ply", slam.map());
  save_map(o.out / "map.glb", slam.map());
  // The final map seen from every keyframe.
  std::filesystem::create_directories(o.out / "keyframes");
  std::size_t k = 0;
  for (std::size_t i = 0; i < records.size(); ++i) {
    if (!records[i].keyframe) continue;
    const splat::Camera cam = splat::posed(dataset.intrinsics, records[i].T_world_cam.inverse());
    const splat::ForwardResult f = rasterizer->forward(slam.map(), cam, {});
    char name[32];
    std::snprintf(name, sizeof(name), "kf_%04zu", i);
    write_png_rgb(o.out / "keyframes" / (std::string(name) + ".png"), f.width, f.height, f.rgb);
    write_render_exr(o.out / "keyframes" / (std::string(name) + ".exr"), f.width, f.height, f.rgb, f.alpha, f.depth_normalized);
    ++k;
  }
  summary(true);
  std::printf("reconstructed %zu frames (%zu keyframes, %zu tracking failures) into %zu Gaussians at %.2f frames/s -> %s\n",
              records.size(), slam.keyframes_added(), failures, slam.map().size(),
              static_cast<double>(records.size()) / progress.elapsed_seconds(), o.out.c_str());
  return 0;
}

}  // namespace app
