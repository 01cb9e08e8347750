#include "batch/benchmark_table.h"

#include <cstdio>
#include <fstream>

#include "io/json_file.h"
#include "splat/error.h"

namespace app {
namespace {

std::string format(const char* pattern, double value) {
  char text[64];
  std::snprintf(text, sizeof text, pattern, value);
  return text;
}

}  // namespace

BenchmarkRow read_benchmark_row(const std::string& sequence, const std::filesystem::path& run) {
  const nlohmann::json summary = read_json_object(run / "summary.json");
  const nlohmann::json eval = read_json_object(run / "eval.json");
  BenchmarkRow r;
  r.sequence = sequence;
  try {
    r.frames = summary.at("frames").get<std::size_t>();
    const double seconds = summary.at("seconds").get<double>();
    const double sweep = summary.contains("refinement") ? summary["refinement"].at("seconds").get<double>() : 0.0;
    r.fps_overall = static_cast<double>(r.frames) / std::max(seconds, 1e-9);
    r.fps_through = static_cast<double>(r.frames) / std::max(seconds - sweep, 1e-9);
    r.peak_memory_mib = summary.at("peak_memory_mib").get<double>();
  } catch (const nlohmann::json::exception& e) {
    throw splat::Error((run / "summary.json").string() + ": " + e.what());
  }
  try {
    r.ate_cm = 100 * eval.at("ate").at("rmse_m").get<double>();
    r.rpe_cm = 100 * eval.at("rpe_1s").at("translation_rmse_m").get<double>();
    r.rpe_deg = eval.at("rpe_1s").at("rotation_rmse_deg").get<double>();
    const nlohmann::json& rendering = eval.at("rendering");
    r.psnr_db = rendering.at("psnr_db").get<double>();
    r.ssim = rendering.at("ssim").get<double>();
    r.depth_l1_cm = 100 * rendering.at("depth_l1_m").get<double>();
    if (eval.contains("held_out_rendering")) r.held_out_psnr_db = eval["held_out_rendering"].at("psnr_db").get<double>();
  } catch (const nlohmann::json::exception& e) {
    throw splat::Error((run / "eval.json").string() + ": " + e.what());
  }
  return r;
}

BenchmarkRow failed_row(const std::string& sequence, const std::string& status, const std::string& error) {
  BenchmarkRow r;
  r.sequence = sequence;
  r.status = status;
  r.error = error;
  return r;
}

std::optional<BenchmarkRow> benchmark_mean(const std::vector<BenchmarkRow>& rows) {
  BenchmarkRow mean;
  mean.sequence = "mean";
  std::size_t n = 0, held_out = 0, baseline = 0;
  double held_out_sum = 0, baseline_sum = 0;
  for (const BenchmarkRow& r : rows) {
    if (r.status != "ok") continue;
    ++n;
    mean.frames += r.frames;
    mean.ate_cm += r.ate_cm, mean.rpe_cm += r.rpe_cm, mean.rpe_deg += r.rpe_deg;
    mean.psnr_db += r.psnr_db, mean.ssim += r.ssim, mean.depth_l1_cm += r.depth_l1_cm;
    mean.fps_through += r.fps_through, mean.fps_overall += r.fps_overall;
    mean.peak_memory_mib = std::max(mean.peak_memory_mib, r.peak_memory_mib);
    if (r.held_out_psnr_db) held_out_sum += *r.held_out_psnr_db, ++held_out;
    if (r.baseline_ate_cm) baseline_sum += *r.baseline_ate_cm, ++baseline;
  }
  if (n == 0) return std::nullopt;
  const double k = static_cast<double>(n);
  for (double* v : {&mean.ate_cm, &mean.rpe_cm, &mean.rpe_deg, &mean.psnr_db, &mean.ssim, &mean.depth_l1_cm,
                    &mean.fps_through, &mean.fps_overall}) {
    *v /= k;
  }
  if (held_out > 0) mean.held_out_psnr_db = held_out_sum / static_cast<double>(held_out);
  if (baseline == n) mean.baseline_ate_cm = baseline_sum / k;  // over the same sequences, or none
  return mean;
}

std::string benchmark_markdown(const std::vector<BenchmarkRow>& rows) {
  std::string md =
      "| sequence | frames | ATE RMSE (cm) | RPE 1 s (cm / deg) | PSNR (dB) | SSIM | depth L1 (cm) | held-out PSNR (dB) "
      "| frames/s (through / overall) | peak memory (MiB) | OpenCV odometry ATE (cm) |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|\n";
  const auto line = [&](const BenchmarkRow& r, bool bold) {
    if (r.status != "ok") {
      md += "| " + r.sequence + " | " + r.status + ": " + r.error + " | | | | | | | | | |\n";
      return;
    }
    const std::string b = bold ? "**" : "";
    md += "| " + b + r.sequence + b + " | " + std::to_string(r.frames) + " | " + b + format("%.2f", r.ate_cm) + b + " | " +
          format("%.2f", r.rpe_cm) + " / " + format("%.2f", r.rpe_deg) + " | " + format("%.2f", r.psnr_db) + " | " +
          format("%.3f", r.ssim) + " | " + format("%.2f", r.depth_l1_cm) + " | " +
          (r.held_out_psnr_db ? format("%.2f", *r.held_out_psnr_db) : std::string("-")) + " | " +
          format("%.2f", r.fps_through) + " / " + format("%.2f", r.fps_overall) + " | " + format("%.0f", r.peak_memory_mib) +
          " | " + (r.baseline_ate_cm ? format("%.2f", *r.baseline_ate_cm) : std::string("-")) + " |\n";
  };
  for (const BenchmarkRow& r : rows) line(r, false);
  if (const auto mean = benchmark_mean(rows)) line(*mean, true);
  return md;
}

namespace {
nlohmann::json row_json(const BenchmarkRow& r) {
  nlohmann::json j = {{"sequence", r.sequence}, {"status", r.status}};
  if (r.status != "ok") {
    j["error"] = r.error;
    return j;
  }
  j.update({{"frames", r.frames},
            {"ate_rmse_cm", r.ate_cm},
            {"rpe_1s_cm", r.rpe_cm},
            {"rpe_1s_deg", r.rpe_deg},
            {"psnr_db", r.psnr_db},
            {"ssim", r.ssim},
            {"depth_l1_cm", r.depth_l1_cm},
            {"held_out_psnr_db", r.held_out_psnr_db ? nlohmann::json(*r.held_out_psnr_db) : nlohmann::json()},
            {"fps_through", r.fps_through},
            {"fps_overall", r.fps_overall},
            {"peak_memory_mib", r.peak_memory_mib},
            {"baseline_opencv_ate_rmse_cm", r.baseline_ate_cm ? nlohmann::json(*r.baseline_ate_cm) : nlohmann::json()}});
  return j;
}
}  // namespace

nlohmann::json benchmark_json(const std::vector<BenchmarkRow>& rows) {
  nlohmann::json sequences = nlohmann::json::array();
  for (const BenchmarkRow& r : rows) sequences.push_back(row_json(r));
  const auto mean = benchmark_mean(rows);
  return {{"sequences", sequences}, {"mean", mean ? row_json(*mean) : nlohmann::json()}};
}

}  // namespace app
