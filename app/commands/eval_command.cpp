#include "commands/eval_command.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <optional>

#include <nlohmann/json.hpp>

#include "io/atomic_file.h"
#include "evaluation/trajectory_errors.h"
#include "commands/label_maps.h"
#include "commands/run_input.h"
#include "io/image_io.h"
#include "io/map_io.h"
#include "io/plot.h"
#include "io/run_folder.h"
#include "commands/progress.h"
#include "mapping/label_fusion.h"
#include "mapping/vignetting.h"
#include "splat/error.h"
#include "splat/losses.h"

namespace app {
namespace {

// The camera vignetting the run estimated (summary.json "vignetting"), or none.
mapping::Vignetting run_vignetting(const std::filesystem::path& run) {
  mapping::Vignetting v;
  std::ifstream in(run / "summary.json");
  if (!in) return v;
  const nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded()) throw splat::Error((run / "summary.json").string() + ": not valid JSON");
  if (!j.contains("vignetting")) return v;
  const nlohmann::json& k = j["vignetting"];
  if (!k.is_object() || !k.contains("k1") || !k.contains("k2") || !k["k1"].is_number() || !k["k2"].is_number()) {
    throw splat::Error((run / "summary.json").string() + ": \"vignetting\" needs numbers k1 and k2");
  }
  v.k1 = k["k1"].get<double>();
  v.k2 = k["k2"].get<double>();
  if (!std::isfinite(v.k1) || !std::isfinite(v.k2)) throw splat::Error((run / "summary.json").string() + ": vignetting is not finite");
  return v;
}

// Rendering quality summed over a set of views.
struct RenderStats {
  double psnr = 0, psnr_masked = 0, ssim = 0, depth_l1 = 0, psnr_radiance = 0;
  std::size_t frames = 0;
  nlohmann::json to_json() const {
    const double n = std::max<double>(1, static_cast<double>(frames));
    return {{"frames", frames}, {"psnr_db", psnr / n}, {"ssim", ssim / n}, {"depth_l1_m", depth_l1 / n},
            {"psnr_masked_valid_depth_db", psnr_masked / n}, {"psnr_without_vignetting_db", psnr_radiance / n}};
  }
};

}  // namespace

int run_eval(const EvalOptions& o) {
  RecordedInput recorded;
  // The run's files must all be its own: a trajectory of one run scored against another's map
  // would be a wrong result with exit 0.
  {
    std::ifstream in(o.run / "summary.json");
    if (!in) throw splat::Error((o.run / "summary.json").string() + ": cannot open file (not a run folder?)");
    const nlohmann::json summary = nlohmann::json::parse(in, nullptr, false);
    if (summary.is_discarded()) throw splat::Error((o.run / "summary.json").string() + ": not valid JSON");
    check_run_manifest(o.run, summary);
    // Runs of `live`, or of earlier versions, recorded no input.
    if (summary.contains("input")) recorded = recorded_input(summary["input"], (o.run / "summary.json").string());
  }
  // The run's own dataset, camera and depth units unless the command line says otherwise.
  const std::filesystem::path dataset_path = o.dataset.empty() ? recorded.dataset : o.dataset;
  if (dataset_path.empty()) throw splat::Error((o.run / "summary.json").string() + ": names no dataset; give --dataset");
  DatasetOptions options = o.dataset_options;
  if (options.intrinsics.empty()) options.intrinsics = recorded.options.intrinsics;
  if (!(options.depth_scale > 0)) options.depth_scale = recorded.options.depth_scale;
  if (options.max_frames == 0) options.max_frames = recorded.options.max_frames;
  if (options.color_camera.empty()) options.color_camera = recorded.options.color_camera;  // the map's colour
  if (o.dataset.empty()) {  // a recording's topics and /tf frames, as the run read it
    if (options.color_topic.empty()) options.color_topic = recorded.options.color_topic;
    if (options.depth_topic.empty()) options.depth_topic = recorded.options.depth_topic;
    if (options.gt_frames.empty()) options.gt_frames = recorded.options.gt_frames;
  }
  const Dataset dataset = open_dataset(dataset_path, options);
  if (!dataset.has_ground_truth()) throw splat::Error(dataset_path.string() + ": the dataset has no ground truth");
  const std::vector<StampedPose> estimate = read_tum_trajectory(o.run / "trajectory.txt");
  std::vector<StampedPose> truth;
  for (const auto& e : dataset.entries) {
    if (e.T_world_cam_truth) truth.push_back({e.timestamp, *e.T_world_cam_truth});
  }
  const TrajectoryErrors errors = evaluate_trajectory(estimate, truth, o.sim3);

  // Rendering quality at the estimated pose of every (N-th) input frame.
  const LoadedMap map = load_map(o.run / "map.ply");
  std::string note;
  auto rasterizer = make_rasterizer(o.backend, note);
  std::vector<double> ts;
  for (const auto& p : estimate) ts.push_back(p.timestamp);
  std::vector<double> te;
  for (const auto& e : dataset.entries) te.push_back(e.timestamp);
  const auto pairs = associate(te, ts, 1e-4);  // the run's lines carry the frames' own timestamps
  const mapping::Vignetting vignetting = run_vignetting(o.run);
  // Training views (the frames mapping could use) and held-out test views (--test-every), apart.
  RenderStats training, held_out;
  // The map's classes against the label images, where both exist.
  const bool score_labels = !map.labels.empty() && dataset.labels.has_value();
  std::optional<LabelScore> training_labels, held_out_labels;
  if (score_labels) training_labels.emplace(*dataset.labels), held_out_labels.emplace(*dataset.labels);
  std::vector<double> frame_times, frame_psnr, frame_ssim;  // per rendered frame, for the plot
  Progress progress("eval renders", pairs.size(), "frames");
  const std::size_t every = static_cast<std::size_t>(std::max(1, o.every));
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    const bool test_view = is_held_out(pairs[k].first, recorded.test_every);
    if (k % every != 0 && !test_view) continue;  // every test view is scored
    const splat::RgbdFrame frame = dataset.load(pairs[k].first);
    const splat::Camera cam = splat::posed(frame.camera, estimate[pairs[k].second].T_world_cam.inverse());
    splat::ForwardResult f = rasterizer->forward(map.gaussians, cam, {});
    RenderStats& stats = test_view ? held_out : training;
    stats.psnr_radiance += splat::psnr(f.rgb, frame.rgb, 3);
    vignetting.apply(f.rgb, cam);  // compared as the camera records it
    std::vector<float> valid(frame.depth.size()), grad(f.rgb.size());
    for (std::size_t p = 0; p < valid.size(); ++p) valid[p] = frame.depth[p] > 0 ? 1.f : 0.f;
    const double frame_psnr_db = splat::psnr(f.rgb, frame.rgb, 3);
    const double frame_ssim_value = 1 - splat::dssim_loss<float>(f.rgb, frame.rgb, frame.width(), frame.height(), 3, grad);
    if (!test_view) {
      frame_times.push_back(frame.timestamp);
      frame_psnr.push_back(frame_psnr_db);
      frame_ssim.push_back(frame_ssim_value);
    }
    stats.psnr += frame_psnr_db;
    stats.psnr_masked += splat::psnr(f.rgb, frame.rgb, 3, valid);
    stats.ssim += frame_ssim_value;
    std::vector<float> dgrad(f.depth.size());
    stats.depth_l1 += splat::depth_l1_loss<float>(f.depth_normalized, frame.depth, {}, dgrad);
    ++stats.frames;
    if (score_labels && !frame.labels.empty()) {
      (test_view ? held_out_labels : training_labels)->add(mapping::render_labels(*rasterizer, map.gaussians, map.labels, cam), frame.labels);
    }
    progress.update(k + 1);
  }
  progress.finish();
  const double n = std::max<double>(1, static_cast<double>(training.frames));
  const double psnr = training.psnr, ssim = training.ssim, psnr_masked = training.psnr_masked,
               psnr_radiance = training.psnr_radiance, depth_l1 = training.depth_l1;

  nlohmann::json rendering = training.to_json();
  rendering["vignetting"] = {{"k1", vignetting.k1}, {"k2", vignetting.k2}};
  rendering["per_frame"] = {{"timestamp", frame_times}, {"psnr_db", frame_psnr}, {"ssim", frame_ssim}};
  nlohmann::json j = {
      {"run", o.run.string()},
      {"dataset", dataset_path.string()},
      {"alignment", o.sim3 ? "sim3" : "se3"},
      {"ate", {{"rmse_m", errors.ate_rmse}, {"mean_m", errors.ate_mean}, {"max_m", errors.ate_max}, {"matched_frames", errors.matched}, {"scale", errors.scale}}},
      {"rpe_1s", {{"translation_rmse_m", errors.rpe_translation_rmse}, {"rotation_rmse_deg", errors.rpe_rotation_rmse_deg}, {"pairs", errors.rpe_pairs}}},
      {"rendering", rendering},
      {"gaussians", map.gaussians.size()},
  };
  if (recorded.test_every > 0) {
    j["held_out_rendering"] = held_out.to_json();
    j["held_out_rendering"]["test_every"] = recorded.test_every;
  }
  if (score_labels) {
    j["labels"] = training_labels->json();
    if (held_out_labels->views() > 0) j["labels"]["held_out"] = held_out_labels->json();
  }
  write_json(o.run / "eval.json", j);

  // Plots: top view (the two axes along which the truth moves most) and error over time.
  Eigen::Vector3d lo = errors.truth.front(), hi = lo;
  for (const auto& p : errors.truth) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  const Eigen::Vector3d extent = hi - lo;
  int a = 0, b = 1;
  if (extent[2] > extent[a] && extent[2] > extent[b]) (extent[0] < extent[1] ? a : b) = 2;
  if (a > b) std::swap(a, b);
  LinePlot top(640, 640);
  top.equal_axes(true);
  std::vector<double> gx, gy, ex, ey;
  for (std::size_t k = 0; k < errors.truth.size(); ++k) {
    gx.push_back(errors.truth[k][a]), gy.push_back(errors.truth[k][b]);
    ex.push_back(errors.aligned_estimate[k][a]), ey.push_back(errors.aligned_estimate[k][b]);
  }
  const char* axis_names[3] = {"x", "y", "z"};
  top.labels(std::string(axis_names[a]) + " (m)", std::string(axis_names[b]) + " (m)");
  top.title("top view, estimate aligned to ground truth");
  top.add(gx, gy, {40, 40, 40}, "ground truth");
  std::vector<double> error_cm;
  for (double e : errors.ate_errors) error_cm.push_back(100 * e);
  top.add_coloured(ex, ey, error_cm, "estimate, error (cm)");
  top.mark(gx.front(), gy.front(), {40, 180, 60}, "start");
  top.mark(gx.back(), gy.back(), {220, 30, 30}, "end");
  write_png_rgb8(o.run / "trajectory_top.png", top.render());
  LinePlot curve(800, 300);
  std::vector<double> t, e;
  for (std::size_t k = 0; k < errors.times.size(); ++k) t.push_back(errors.times[k] - errors.times.front()), e.push_back(errors.ate_errors[k] * 100);
  curve.labels("time (s)", "ATE (cm)");
  char rmse[64];
  std::snprintf(rmse, sizeof rmse, "position error after alignment, RMSE %.2f cm", errors.ate_rmse * 100);
  curve.title(rmse);
  curve.add(t, e, {30, 60, 200});
  write_png_rgb8(o.run / "ate_over_time.png", curve.render());
  if (!frame_times.empty()) {
    LinePlot quality(800, 300);
    std::vector<double> since_start;
    for (double ts_frame : frame_times) since_start.push_back(ts_frame - frame_times.front());
    quality.labels("time (s)", "PSNR (dB)");
    char mean[64];
    std::snprintf(mean, sizeof mean, "PSNR of the final map at each input frame, mean %.2f dB", psnr / n);
    quality.title(mean);
    quality.add(since_start, frame_psnr, {30, 140, 60});
    write_png_rgb8(o.run / "psnr_over_time.png", quality.render());
  }

  std::printf("ATE RMSE %.2f cm over %zu frames, RPE(1 s) %.2f cm / %.2f deg, PSNR %.2f dB (%.2f dB over valid depth, %.2f dB without vignetting), SSIM %.3f, depth L1 %.2f cm",
              errors.ate_rmse * 100, errors.matched, errors.rpe_translation_rmse * 100, errors.rpe_rotation_rmse_deg,
              psnr / n, psnr_masked / n, psnr_radiance / n, ssim / n, depth_l1 / n * 100);
  if (held_out.frames > 0) {
    const double h = static_cast<double>(held_out.frames);
    std::printf("; held-out views (%zu): PSNR %.2f dB, SSIM %.3f, depth L1 %.2f cm", held_out.frames,
                held_out.psnr / h, held_out.ssim / h, held_out.depth_l1 / h * 100);
  }
  if (score_labels) {
    std::printf("; labels: mIoU %.3f", training_labels->miou());
    if (held_out_labels->views() > 0) std::printf(" (held-out views %.3f)", held_out_labels->miou());
  }
  std::printf(" -> %s\n", (o.run / "eval.json").c_str());
  return 0;
}

}  // namespace app
