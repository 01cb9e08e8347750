#include "commands/benchmark_command.h"

#include <cstdio>
#include <fstream>

#include <nlohmann/json.hpp>

#include "batch/benchmark_table.h"
#include "batch/child_process.h"
#include "batch/opencv_baseline.h"
#include "batch/sequence_finder.h"
#include "commands/evaluation.h"
#include "commands/interrupt.h"
#include "commands/progress.h"
#include "io/atomic_file.h"
#include "io/run_folder.h"
#include "io/slam_config_io.h"
#include "splat/error.h"

namespace app {
namespace {

nlohmann::json read_json_or_null(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) return nullptr;
  nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  return j.is_discarded() ? nlohmann::json() : j;
}

// Whether `run` holds a finished, evaluated run of `sequence` with these settings.
bool finished_with(const std::filesystem::path& run, const FoundSequence& sequence, const BenchmarkOptions& o,
                   const nlohmann::json& config) {
  const nlohmann::json summary = read_json_or_null(run / "summary.json");
  if (!summary.is_object() || !summary.value("complete", false) || !summary.contains("input")) return false;
  if (!std::filesystem::exists(run / "eval.json")) return false;
  const nlohmann::json& input = summary["input"];
  if (input.value("dataset", "") != std::filesystem::absolute(sequence.path).string() ||
      input.value("test_every", -1) != o.test_every || input.value("max_frames", -1) != o.max_frames ||
      input.value("config", nlohmann::json()) != config) {
    return false;
  }
  try {
    check_run_manifest(run, summary);
  } catch (const splat::Error&) {
    return false;
  }
  return std::filesystem::last_write_time(run / "eval.json") >= std::filesystem::last_write_time(run / "summary.json");
}

std::vector<std::string> backend_args(const BackendChoice& b) {
  std::vector<std::string> args = {"--backend", b.backend, "--threads", std::to_string(b.threads)};
  if (b.device >= 0) args.insert(args.end(), {"--device", std::to_string(b.device)});
  return args;
}

// The baseline's ATE on a sequence (cm), computed once per sequence and frame count and kept in
// OUT/baselines/NAME.json beside its trajectory.
double baseline_ate_cm(const FoundSequence& s, const BenchmarkOptions& o) {
  const std::filesystem::path dir = o.out / "baselines", record = dir / (s.name + ".json");
  const std::string dataset = std::filesystem::absolute(s.path).string();
  const nlohmann::json kept = read_json_or_null(record);
  if (kept.is_object() && kept.value("dataset", "") == dataset && kept.value("max_frames", -1) == o.max_frames &&
      kept.contains("ate_rmse_cm") && kept["ate_rmse_cm"].is_number()) {
    return kept["ate_rmse_cm"].get<double>();
  }
  DatasetOptions options;
  options.max_frames = o.max_frames;
  const Dataset d = open_dataset(s.path, options);
  std::vector<StampedPose> truth;
  for (const DatasetEntry& e : d.entries) {
    if (e.T_world_cam_truth) truth.push_back({e.timestamp, *e.T_world_cam_truth});
  }
  Progress progress("  OpenCV odometry baseline", d.entries.size(), "frames");
  const BaselineTrajectory baseline =
      opencv_odometry_baseline(d, [&](std::size_t done, std::size_t) { progress.update(done); });
  progress.finish();
  const double ate_cm = 100 * evaluate_trajectory(baseline.poses, truth).ate_rmse;
  std::filesystem::create_directories(dir);
  write_tum_trajectory(dir / (s.name + ".txt"), baseline.poses);
  write_json(record, {{"dataset", dataset}, {"max_frames", o.max_frames}, {"ate_rmse_cm", ate_cm},
                      {"failures", baseline.failures}, {"method", "cv::rgbd::RgbdOdometry, frame to frame, defaults"}});
  return ate_cm;
}

void write_tables(const std::filesystem::path& out, const std::vector<BenchmarkRow>& rows) {
  write_atomically(out / "benchmark.md", [&](const std::filesystem::path& tmp) {
    std::ofstream(tmp) << benchmark_markdown(rows);
  });
  write_json(out / "benchmark.json", benchmark_json(rows));
}

}  // namespace

int run_benchmark(const BenchmarkOptions& o) {
  const std::vector<FoundSequence> sequences = find_sequences(o.root);
  if (sequences.empty()) {
    throw splat::Error(o.root.string() + ": no sequence found below it (TUM or plain rgb.txt + depth.txt, Replica "
                       "results/ + traj.txt, or rgb/ + depth/ + intrinsics.txt folders)");
  }
  const nlohmann::json config = slam_config_to_json(load_slam_config(o.config));  // a bad file costs nothing
  std::filesystem::create_directories(o.out / "logs");
  const std::string gslam = this_executable().string();
  const InterruptGuard interrupt;
  std::vector<BenchmarkRow> rows;
  std::size_t failed = 0;
  for (std::size_t i = 0; i < sequences.size() && !InterruptGuard::interrupted(); ++i) {
    const FoundSequence& s = sequences[i];
    const std::filesystem::path run = o.out / s.name, log = o.out / "logs" / (s.name + ".log");
    std::fprintf(stderr, "benchmark %zu/%zu: %s (%s)", i + 1, sequences.size(), s.name.c_str(), s.path.c_str());
    if (finished_with(run, s, o, config)) {
      std::fprintf(stderr, ": finished earlier\n");
      rows.push_back(read_benchmark_row(s.name, run));
      if (o.baseline) rows.back().baseline_ate_cm = baseline_ate_cm(s, o);
      continue;
    }
    std::fprintf(stderr, ", log %s\n", log.c_str());
    std::vector<std::string> reconstruct = {gslam, "reconstruct", "--out", run.string()};
    if (std::filesystem::exists(run / "checkpoint.bin")) {
      reconstruct.push_back("--resume");  // an interrupted run continues where it stopped
    } else {
      reconstruct.insert(reconstruct.end(), {s.path.string(), "--overwrite", "--test-every", std::to_string(o.test_every),
                                             "--max-frames", std::to_string(o.max_frames)});
      if (!o.config.empty()) reconstruct.insert(reconstruct.end(), {"--config", o.config.string()});
    }
    for (const std::string& a : backend_args(o.backend)) reconstruct.push_back(a);
    std::vector<std::string> eval = {gslam, "eval", run.string()};
    for (const std::string& a : backend_args(o.backend)) eval.push_back(a);

    int code = run_logged(reconstruct, log);
    const nlohmann::json summary = read_json_or_null(run / "summary.json");
    if (code == 0 && !(summary.is_object() && summary.value("complete", false))) {
      rows.push_back(failed_row(s.name, "interrupted", "the same command resumes it"));
    } else if (code != 0) {
      rows.push_back(failed_row(s.name, "failed", "reconstruct: " + last_line(log)));
    } else if ((code = run_logged(eval, log)) != 0) {
      rows.push_back(failed_row(s.name, "failed", "eval: " + last_line(log)));
    } else {
      rows.push_back(read_benchmark_row(s.name, run));
      if (o.baseline) rows.back().baseline_ate_cm = baseline_ate_cm(s, o);
    }
    failed += rows.back().status == "failed";
    const BenchmarkRow& r = rows.back();
    if (r.status == "ok") {
      std::fprintf(stderr, "  ATE %.2f cm, PSNR %.2f dB, %.2f frames/s", r.ate_cm, r.psnr_db, r.fps_overall);
      if (r.baseline_ate_cm) std::fprintf(stderr, "; OpenCV odometry ATE %.2f cm", *r.baseline_ate_cm);
      std::fprintf(stderr, "\n");
    } else {
      std::fprintf(stderr, "  %s: %s\n", r.status.c_str(), r.error.c_str());
    }
    write_tables(o.out, rows);
  }
  write_tables(o.out, rows);
  std::printf("%s", benchmark_markdown(rows).c_str());
  if (InterruptGuard::interrupted()) {
    std::fprintf(stderr, "interrupted after %zu of %zu sequences; the same command continues\n", rows.size(),
                 sequences.size());
  }
  std::fprintf(stderr, "tables: %s, %s\n", (o.out / "benchmark.md").c_str(), (o.out / "benchmark.json").c_str());
  if (failed > 0) {
    std::fprintf(stderr, "benchmark: %zu of %zu sequences failed\n", failed, sequences.size());
    return 1;
  }
  return 0;
}

}  // namespace app
