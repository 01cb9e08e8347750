#include "commands/sequence_run.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <nlohmann/json.hpp>

#include "batch/batch_table.h"
#include "batch/benchmark_table.h"
#include "batch/opencv_baseline.h"
#include "batch/slurm.h"
#include "commands/progress.h"
#include "evaluation/trajectory_errors.h"
#include "io/atomic_file.h"
#include "io/json_file.h"
#include "process/child_process.h"
#include "splat/error.h"

namespace app {
namespace {

std::vector<std::string> backend_args(const BackendChoice& b) {
  std::vector<std::string> args = {"--backend", b.backend, "--threads", std::to_string(b.threads)};
  if (b.device >= 0) args.insert(args.end(), {"--device", std::to_string(b.device)});
  return args;
}

// The baseline's ATE on a sequence (cm), computed once per sequence and frame count and kept in
// OUT/baselines/NAME.json beside its trajectory.
double baseline_ate_cm(const FoundSequence& s, const BenchmarkOptions& o) {
  const std::filesystem::path dir = o.out / "baselines", record = dir / (s.name + ".json");
  const std::string dataset = s.path.string();
  DatasetOptions options;
  options.max_frames = o.max_frames;
  const Dataset d = open_dataset(s.path, options);
  // The frames as read: a camera or lens read differently (a newer gslam) makes another baseline.
  const std::string camera =
      intrinsics_text(d.undistortion ? d.undistortion->raw_camera() : d.intrinsics, d.distortion) + "; colour " +
      ColorResampler::record(d.color_registration.get());
  const nlohmann::json kept = read_json_or_null(record);
  if (kept.is_object() && kept.value("dataset", "") == dataset &&
      kept.value("camera", "") == camera && kept.value("max_frames", -1) == o.max_frames &&
      kept.contains("ate_rmse_cm") && kept["ate_rmse_cm"].is_number()) {
    return kept["ate_rmse_cm"].get<double>();
  }
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
  write_json(record, {{"dataset", dataset},
                      {"camera", camera},
                      {"max_frames", o.max_frames},
                      {"ate_rmse_cm", ate_cm},
                      {"failures", baseline.failures},
                      {"method", "cv::rgbd::RgbdOdometry, frame to frame, defaults"}});
  return ate_cm;
}

struct Outcome {
  std::string status = "ok";  // ok, failed, interrupted
  std::string error;
};

Outcome run_commands(const RunPlan& plan, std::size_t index) {
  const BenchmarkOptions& o = plan.options;
  const FoundSequence& s = plan.sequences[index];
  const std::filesystem::path run = run_folder(plan, index), log = sequence_log(plan, index);
  const std::string gslam = this_executable().string();
  std::vector<std::string> reconstruct = {gslam, "reconstruct", "--out", run.string()};
  if (std::filesystem::exists(run / "checkpoint.bin")) {
    reconstruct.push_back("--resume");  // an interrupted run continues where it stopped
  } else {
    reconstruct.insert(reconstruct.end(), {s.path.string(), "--overwrite", "--test-every",
                                           std::to_string(o.test_every), "--max-frames",
                                           std::to_string(o.max_frames)});
    if (!o.config.empty()) reconstruct.insert(reconstruct.end(), {"--config", o.config.string()});
  }
  for (const std::string& a : backend_args(o.backend)) reconstruct.push_back(a);
  const int code = run_logged(reconstruct, log);
  const nlohmann::json summary = read_json_or_null(run / "summary.json");
  if (code != 0) return {"failed", "reconstruct: " + last_line(log)};
  if (!(summary.is_object() && summary.value("complete", false)))
    return {"interrupted", "the same command resumes it"};
  if (!o.evaluate) return {};
  std::vector<std::string> eval = {gslam, "eval", run.string()};
  for (const std::string& a : backend_args(o.backend)) eval.push_back(a);
  if (run_logged(eval, log) != 0) return {"failed", "eval: " + last_line(log)};
  if (o.baseline) baseline_ate_cm(s, o);  // kept for the merge
  return {};
}

// What became of sequence `index`, from its files. Only its task's files are read: a sequence
// not to run finished before, as make_run_plan checked (checksums and all), and a task's
// outcome file is written after its run finished; so a merge reads each run folder once.
Outcome outcome_of(const RunPlan& plan, std::size_t index) {
  const auto task = std::find(plan.to_run.begin(), plan.to_run.end(), index);
  if (task == plan.to_run.end()) return {};
  const std::filesystem::path log =
      task_log(plan.options.out, static_cast<std::size_t>(task - plan.to_run.begin()));
  // Slurm's own word on a task it cancelled or killed comes first: the task may have gone on
  // to write an outcome of its own (interrupted by the signal).
  if (const std::string slurm = slurmstepd_error(log); !slurm.empty()) return {"failed", slurm};
  const nlohmann::json written = read_json_or_null(outcome_file(plan, index));
  if (written.is_object()) return {written.value("status", "failed"), written.value("error", "")};
  // Killed: the last words of its task, else of its commands.
  for (const std::filesystem::path& file : {log, sequence_log(plan, index)}) {
    if (const std::string line = last_line(file); !line.empty()) return {"failed", line};
  }
  return {"interrupted", "not run; the same command runs it"};
}

template <typename Row>
Row row_of(const RunPlan& plan, std::size_t index, const Outcome& outcome);

template <>
BenchmarkRow row_of(const RunPlan& plan, std::size_t index, const Outcome& outcome) {
  const FoundSequence& s = plan.sequences[index];
  if (outcome.status != "ok") return failed_row(s.name, outcome.status, outcome.error);
  BenchmarkRow row = read_benchmark_row(s.name, run_folder(plan, index));
  if (plan.options.baseline) row.baseline_ate_cm = baseline_ate_cm(s, plan.options);
  return row;
}

template <>
BatchRow row_of(const RunPlan& plan, std::size_t index, const Outcome& outcome) {
  const FoundSequence& s = plan.sequences[index];
  if (outcome.status == "ok") return read_batch_row(s.name, run_folder(plan, index));
  BatchRow row;
  row.sequence = s.name;
  row.status = outcome.status;
  row.error = outcome.error;
  return row;
}

MergedTable table_files(const RunPlan& plan) {
  MergedTable table;
  const std::string name = plan.options.evaluate ? "benchmark" : "batch";
  table.markdown_file = plan.options.out / (name + ".md");
  table.json_file = plan.options.out / (name + ".json");
  return table;
}

template <typename Row>
MergedTable merge(const RunPlan& plan, std::string (*markdown)(const std::vector<Row>&),
                  nlohmann::json (*json)(const std::vector<Row>&)) {
  std::vector<Row> rows;
  MergedTable table = table_files(plan);
  for (std::size_t i = 0; i < plan.sequences.size(); ++i) {
    try {
      rows.push_back(row_of<Row>(plan, i, outcome_of(plan, i)));
    } catch (const splat::Error& e) {  // a run folder changed since: its row says how
      rows.push_back(row_of<Row>(plan, i, {"failed", e.what()}));
    }
    table.failed += rows.back().status == "failed";
  }
  table.markdown = markdown(rows);
  write_atomically(table.markdown_file,
                   [&](const std::filesystem::path& tmp) { std::ofstream(tmp) << table.markdown; });
  write_json(table.json_file, json(rows));
  return table;
}

}  // namespace

bool run_planned_sequence(const RunPlan& plan, std::size_t index) {
  const std::filesystem::path result = outcome_file(plan, index);
  std::filesystem::create_directories(result.parent_path());
  std::filesystem::create_directories(sequence_log(plan, index).parent_path());
  std::filesystem::remove(result);
  const Outcome outcome = run_commands(plan, index);
  write_json(result, {{"status", outcome.status}, {"error", outcome.error}});
  const std::string& name = plan.sequences[index].name;
  if (outcome.status == "ok" && plan.options.evaluate) {
    const BenchmarkRow r = row_of<BenchmarkRow>(plan, index, outcome);
    std::fprintf(stderr, "  %s: ATE %.2f cm, PSNR %.2f dB, %.2f frames/s", name.c_str(), r.ate_cm,
                 r.psnr_db, r.fps_overall);
    if (r.baseline_ate_cm)
      std::fprintf(stderr, "; OpenCV odometry ATE %.2f cm", *r.baseline_ate_cm);
    std::fprintf(stderr, "\n");
  } else if (outcome.status == "ok") {
    const BatchRow r = row_of<BatchRow>(plan, index, outcome);
    std::fprintf(stderr, "  %s: %zu frames, %zu Gaussians, %.2f frames/s\n", name.c_str(), r.frames,
                 r.gaussians, r.fps);
  } else {
    std::fprintf(stderr, "  %s: %s: %s\n", name.c_str(), outcome.status.c_str(),
                 outcome.error.c_str());
  }
  return outcome.status == "ok";
}

MergedTable merge_run_tables(const RunPlan& plan) {
  if (plan.options.evaluate) return merge<BenchmarkRow>(plan, benchmark_markdown, benchmark_json);
  return merge<BatchRow>(plan, batch_markdown, batch_json);
}

std::optional<MergedTable> read_merged_table(const RunPlan& plan) {
  MergedTable table = table_files(plan);
  std::ifstream markdown(table.markdown_file);
  const nlohmann::json json = read_json_or_null(table.json_file);
  if (!markdown || !json.is_object() || !json.contains("sequences")) return std::nullopt;
  table.markdown.assign(std::istreambuf_iterator<char>(markdown), {});
  for (const nlohmann::json& row : json["sequences"])
    table.failed += row.value("status", "") == "failed";
  return table;
}

int report_table(const MergedTable& table, const RunPlan& plan) {
  std::printf("%s", table.markdown.c_str());
  std::fflush(stdout);
  std::fprintf(stderr, "tables: %s, %s\n", table.markdown_file.c_str(), table.json_file.c_str());
  if (table.failed == 0) return 0;
  std::fprintf(stderr, "%s: %zu of %zu sequences failed\n",
               plan.options.evaluate ? "benchmark" : "batch", table.failed, plan.sequences.size());
  return 1;
}

}  // namespace app
