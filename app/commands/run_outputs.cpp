#include "commands/run_outputs.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <future>
#include <memory>

#include "io/atomic_file.h"
#include "io/gltf_io.h"
#include "io/image_io.h"
#include "io/map_io.h"
#include "io/run_checkpoint.h"
#include "io/run_folder.h"
#include "splat/error.h"
#include "splat/rgbd_frame.h"
#include "viewer/views.h"

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

}  // namespace

RunOutputs::RunOutputs(std::filesystem::path out, std::string input, const splat::Rasterizer& rasterizer,
                       bool overwrite)
    : out_(std::move(out)),
      run_id_(new_run_id()),
      input_(std::move(input)),
      rasterizer_(rasterizer),
      start_(std::chrono::steady_clock::now()) {
  prepare_run_folder(out_, overwrite);
}

RunOutputs::RunOutputs(std::filesystem::path out, std::string input, const splat::Rasterizer& rasterizer,
                       const nlohmann::json& state)
    : out_(std::move(out)),
      input_(std::move(input)),
      rasterizer_(rasterizer),
      start_(std::chrono::steady_clock::now()) {
  try {
    run_id_ = state.at("run_id").get<std::string>();
    earlier_seconds_ = state.at("seconds").get<double>();
    tracking_ms_ = state.at("tracking_ms").get<double>();
    mapping_ms_ = state.at("mapping_ms").get<double>();
    loading_ms_ = state.at("loading_ms").get<double>();
    extra_ = state.at("extra");
    for (const nlohmann::json& f : state.at("frames")) {
      FrameRecord r;
      r.timestamp = f.at("timestamp").get<double>();
      r.T_world_cam = pose_from_json(f.at("T_world_cam"));
      r.tracked = f.at("tracked").get<bool>();
      r.retried = f.at("retried").get<bool>();
      r.relocalized = f.value("relocalized", false);
      r.reason = f.at("reason").get<std::string>();
      r.keyframe = f.at("keyframe").get<bool>();
      r.held_out = f.at("held_out").get<bool>();
      r.renders = f.at("renders").get<int>();
      r.overlap = f.at("overlap").get<double>();
      r.moving_share = f.value("moving_share", 0.0);
      r.tracking_ms = f.at("tracking_ms").get<double>();
      r.mapping_ms = f.at("mapping_ms").get<double>();
      r.gaussians = f.at("gaussians").get<std::size_t>();
      failures_ += r.tracked ? 0 : 1;
      retries_ += r.retried ? 1 : 0;
      records_.push_back(r);
      trajectory_.push_back({r.timestamp, r.T_world_cam});
    }
  } catch (const nlohmann::json::exception& e) {
    throw splat::Error((out_ / "checkpoint.bin").string() + ": malformed run record: " + e.what());
  }
}

nlohmann::json RunOutputs::state() const {
  nlohmann::json frames = nlohmann::json::array();
  for (const FrameRecord& r : records_) {
    frames.push_back({{"timestamp", r.timestamp}, {"T_world_cam", pose_to_json(r.T_world_cam)},
                      {"tracked", r.tracked}, {"retried", r.retried}, {"relocalized", r.relocalized}, {"reason", r.reason},
                      {"keyframe", r.keyframe}, {"held_out", r.held_out}, {"renders", r.renders}, {"overlap", r.overlap}, {"moving_share", r.moving_share},
                      {"tracking_ms", r.tracking_ms}, {"mapping_ms", r.mapping_ms}, {"gaussians", r.gaussians}});
  }
  return {{"run_id", run_id_}, {"seconds", elapsed_seconds()}, {"tracking_ms", tracking_ms_},
          {"mapping_ms", mapping_ms_}, {"loading_ms", loading_ms_}, {"extra", extra_}, {"frames", frames}};
}

double RunOutputs::elapsed_seconds() const {
  return earlier_seconds_ + std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

void RunOutputs::add(const FrameRecord& record, double loading_ms) {
  tracking_ms_ += record.tracking_ms;
  mapping_ms_ += record.mapping_ms;
  loading_ms_ += loading_ms;
  failures_ += record.tracked ? 0 : 1;
  retries_ += record.retried ? 1 : 0;
  records_.push_back(record);
  trajectory_.push_back({record.timestamp, record.T_world_cam});
}

void RunOutputs::update_poses(const std::vector<Eigen::Isometry3d>& T_world_cam) {
  if (T_world_cam.size() != records_.size()) {
    throw splat::Error("update_poses: " + std::to_string(T_world_cam.size()) + " poses for " +
                       std::to_string(records_.size()) + " frames");
  }
  for (std::size_t i = 0; i < records_.size(); ++i) {
    records_[i].T_world_cam = trajectory_[i].T_world_cam = T_world_cam[i];
  }
}

std::string describe(const LoopEvent& loop) {
  char text[200];
  std::snprintf(text, sizeof text, "loop: frame %zu -> frame %zu, %d inliers, drift %.1f cm / %.1f deg: %s", loop.frame,
                loop.matched_frame, loop.inliers, 100 * loop.drift_m, loop.drift_deg,
                loop.accepted ? "accepted" : "rejected");
  std::string line = text;
  if (loop.confirms_frame)
    line += ", confirming the loop of frame " + std::to_string(*loop.confirms_frame);
  return line;
}

void RunOutputs::set_mapping(const MappingTotals& t, const std::vector<LoopEvent>& loops, bool on_device,
                             bool overlapped) {
  nlohmann::json events = nlohmann::json::array();
  std::size_t accepted = 0;
  for (const LoopEvent& e : loops) {
    accepted += e.accepted;
    events.push_back({{"frame", e.frame},
                      {"matched_frame", e.matched_frame},
                      {"inliers", e.inliers},
                      {"drift_m", e.drift_m},
                      {"drift_deg", e.drift_deg},
                      {"accepted", e.accepted},
                      {"confirms_frame",
                       e.confirms_frame ? nlohmann::json(*e.confirms_frame) : nlohmann::json()}});
  }
  extra_["loops"] = {{"accepted", accepted}, {"rejected", loops.size() - accepted}, {"events", events},
                     {"covisible_edges", t.covisible_edges}, {"covisible_rejected", t.covisible_rejected}};
  extra_["mapping"] = {{"keyframes_mapped", t.keyframes_mapped},   {"keyframes_skipped", t.keyframes_skipped},
                       {"gaussians_added", t.gaussians_added},     {"gaussians_pruned", t.gaussians_pruned},
                       {"ghosts_pruned", t.ghosts_pruned},
                       {"iterations", t.iterations},               {"last_loss", t.last_loss},
                       {"seconds", t.mapping_ms / 1000},           {"on_device", on_device},
                       {"overlapped", overlapped}};
}

nlohmann::json RunOutputs::summary(const splat::Gaussians& map, std::size_t keyframes, bool complete,
                                   const std::vector<std::filesystem::path>& files) const {
  const double seconds = elapsed_seconds();
  const double n = std::max<double>(1, static_cast<double>(records_.size()));
  nlohmann::json j = {
      {"complete", complete},
      {"dataset", input_},
      {"backend", rasterizer_.name()},
      {"frames", records_.size()},
      {"keyframes", keyframes},
      {"gaussians", map.size()},
      {"fps", static_cast<double>(records_.size()) / std::max(seconds, 1e-9)},
      {"seconds", seconds},
      {"time_per_frame_ms",
       {{"tracking", tracking_ms_ / n},
        {"mapping", mapping_ms_ / n},
        {"loading", loading_ms_ / n}}},
      {"tracking_failures", failures_},
      {"tracking_retries", retries_},
      {"tracking_relocalizations", std::count_if(records_.begin(), records_.end(), [](const FrameRecord& r) { return r.relocalized; })},
      {"held_out_frames", std::count_if(records_.begin(), records_.end(), [](const FrameRecord& r) { return r.held_out; })},
      {"peak_memory_mib", peak_memory_mib()},
      {"device_memory_mib", static_cast<double>(rasterizer_.device_memory_bytes()) / (1 << 20)},
      // Host <-> device traffic of the whole run (none on the CPU backend).
      {"transfers_mib",
       {{"to_device", static_cast<double>(rasterizer_.transfers().to_device) / (1 << 20)},
        {"to_host", static_cast<double>(rasterizer_.transfers().to_host) / (1 << 20)}}},
  };
  // Moving objects left out of tracking and mapping: their share of each frame's pixels.
  double moving_sum = 0, moving_max = 0;
  std::size_t moving_frames = 0;
  for (const FrameRecord& r : records_) {
    moving_sum += r.moving_share;
    moving_max = std::max(moving_max, r.moving_share);
    moving_frames += r.moving_share > 0;
  }
  j["dynamic"] = {{"masked_share_mean", moving_sum / n}, {"masked_share_max", moving_max}, {"frames_with_moving", moving_frames},
                  {"ghosts_removed", extra_.contains("mapping") ? extra_["mapping"].value("ghosts_pruned", std::size_t{0}) : 0}};
  if (has_errors_) {
    j["ate_rmse_m"] = errors_.ate_rmse;
    j["ate_matched_frames"] = errors_.matched;
  }
  j.update(extra_);
  j["manifest"] = run_manifest(out_, run_id_, files);
  return j;
}

void RunOutputs::checkpoint(const splat::Gaussians& map, std::size_t keyframes, bool with_map) {
  write_tum_trajectory(out_ / "trajectory.txt", trajectory_);
  if (with_map && !map.empty()) save_map(out_ / "map.ply", map);
  // The map of an earlier checkpoint is this run's too; the manifest lists what is there now.
  write_json(out_ / "summary.json", summary(map, keyframes, false, {"trajectory.txt", "map.ply"}));
}

void RunOutputs::finish(const splat::Gaussians& map, std::size_t keyframes,
                        splat::Rasterizer& rasterizer, const splat::Camera& intrinsics,
                        const std::vector<StampedPose>& truth) {
  write_tum_trajectory(out_ / "trajectory.txt", trajectory_);
  std::vector<std::filesystem::path> files = {"trajectory.txt"};
  if (!map.empty()) {
    files.insert(files.end(), {"map.ply", "map.glb"});
    const splat::GaussianLabels* labels = labels_.size() == map.size() ? &labels_ : nullptr;
    // The world's up (the floor's normal, else the cameras'), recorded and standing map.glb
    // upright in glTF's axes (+Y up).
    Eigen::Quaterniond gltf_from_world = Eigen::Quaterniond::Identity();
    std::vector<Eigen::Isometry3d> poses;
    for (const StampedPose& pose : trajectory_) poses.push_back(pose.T_world_cam);
    try {
      const WorldUp up = estimate_world_up(poses, map);
      extra_["world_up"] = {{"x", up.up.x()}, {"y", up.up.y()}, {"z", up.up.z()}, {"source", up.source_name()}};
      gltf_from_world = gltf_rotation_for_up(up.up);
    } catch (const splat::Error& e) {  // no poses, or cameras that agree on no up: map.glb as it is
      extra_["world_up_unavailable"] = e.what();
    }
    // Files are written on their own threads while the keyframes render: compressing them took
    // most of this (one core) and rendering uses the others.
    std::future<void> maps = std::async(std::launch::async, [&] {
      save_map(out_ / "map.ply", map, Eigen::Quaterniond::Identity(), labels);
      save_map(out_ / "map.glb", map, gltf_from_world, labels);
    });
    // The final map seen from every keyframe.
    std::filesystem::create_directories(out_ / "keyframes");
    std::future<void> png, exr;  // the previous keyframe's files, each on a core of its own
    const auto written = [&] {
      for (std::future<void>* file : {&png, &exr}) {
        if (file->valid()) file->get();
      }
    };
    for (std::size_t i = 0; i < records_.size() && !stopping_; ++i) {
      if (!records_[i].keyframe) continue;
      const splat::Camera cam = splat::posed(intrinsics, records_[i].T_world_cam.inverse());
      auto f = std::make_shared<const splat::ForwardResult>(
          rasterizer.forward(map, cam, splat::images_only()));
      char name[32];
      std::snprintf(name, sizeof(name), "kf_%04zu", i);
      const std::filesystem::path stem = out_ / "keyframes" / name;
      files.push_back(std::filesystem::path("keyframes") / (std::string(name) + ".png"));
      files.push_back(std::filesystem::path("keyframes") / (std::string(name) + ".exr"));
      written();
      png = std::async(std::launch::async, [f, stem] {
        write_png_rgb(std::filesystem::path(stem) += ".png", f->width, f->height, f->rgb);
      });
      exr = std::async(std::launch::async, [f, stem] {
        write_render_exr(std::filesystem::path(stem) += ".exr", f->width, f->height, f->rgb,
                         f->alpha, f->depth_normalized);
      });
    }
    written();
    maps.get();
  }
  if (!truth.empty()) {
    try {
      errors_ = evaluate_trajectory(trajectory_, truth);
      has_errors_ = true;
    } catch (const splat::Error& e) {  // too few frames to align (a short live run): no ATE
      extra_["ate_unavailable"] = e.what();
    }
  }
  write_json(out_ / "summary.json", summary(map, keyframes, !resumable_, files));
  if (map.empty()) {
    throw splat::Error(input_ + ": nothing was reconstructed: no frame of " + std::to_string(records_.size()) +
                       " had usable depth (" + std::to_string(failures_) + " untracked)");
  }
}

}  // namespace app
