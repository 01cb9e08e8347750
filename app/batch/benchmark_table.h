// The table of a benchmark: one row per sequence from its run folder (summary.json, eval.json),
// and the mean over the sequences that finished, as Markdown (the papers' table) and JSON.
#pragma once
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace app {

struct BenchmarkRow {
  std::string sequence;
  std::string status = "ok";  // ok, failed, interrupted
  std::string error;          // failed or interrupted: what happened (the log's last line)
  std::size_t frames = 0;
  double ate_cm = 0, rpe_cm = 0, rpe_deg = 0;  // ATE RMSE; RPE over 1 s, RMSE
  double psnr_db = 0, ssim = 0, depth_l1_cm = 0;   // training views
  std::optional<double> held_out_psnr_db;          // --test-every views
  double fps_through = 0;  // frames / the time taking them (tracking and mapping, no sweep)
  double fps_overall = 0;  // frames / the whole run (with the final sweep)
  double peak_memory_mib = 0;
  std::optional<double> baseline_ate_cm;  // OpenCV's RGB-D odometry on the same frames (opencv_baseline.h)
};

// The row of a finished run folder. Throws splat::Error naming the file for a missing or
// malformed summary.json or eval.json.
BenchmarkRow read_benchmark_row(const std::string& sequence, const std::filesystem::path& run);
BenchmarkRow failed_row(const std::string& sequence, const std::string& status, const std::string& error);

// The mean of each figure over the rows with status ok (frames summed); nullopt if there is none.
std::optional<BenchmarkRow> benchmark_mean(const std::vector<BenchmarkRow>& rows);

// A Markdown table: a line per row, then the mean.
std::string benchmark_markdown(const std::vector<BenchmarkRow>& rows);
// {"sequences": [{...}, ...], "mean": {...} or null}, figures in the units of their names.
nlohmann::json benchmark_json(const std::vector<BenchmarkRow>& rows);

}  // namespace app
