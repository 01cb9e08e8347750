#include "batch/batch_table.h"

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <optional>

#include "io/json_file.h"
#include "splat/error.h"

namespace app {
namespace {

std::optional<BatchRow> batch_total(const std::vector<BatchRow>& rows) {
  BatchRow total;
  total.sequence = "total";
  bool any = false;
  for (const BatchRow& r : rows) {
    if (r.status != "ok") continue;
    any = true;
    total.frames += r.frames, total.keyframes += r.keyframes, total.gaussians += r.gaussians;
    total.seconds += r.seconds;
    total.peak_memory_mib = std::max(total.peak_memory_mib, r.peak_memory_mib);
  }
  if (!any) return std::nullopt;
  total.fps = static_cast<double>(total.frames) / std::max(total.seconds, 1e-9);
  return total;
}

nlohmann::json row_json(const BatchRow& r) {
  nlohmann::json j = {{"sequence", r.sequence}, {"status", r.status}};
  if (r.status != "ok") {
    j["error"] = r.error;
    return j;
  }
  j.update({{"frames", r.frames},
            {"keyframes", r.keyframes},
            {"gaussians", r.gaussians},
            {"seconds", r.seconds},
            {"fps", r.fps},
            {"peak_memory_mib", r.peak_memory_mib}});
  return j;
}

}  // namespace

BatchRow read_batch_row(const std::string& sequence, const std::filesystem::path& run) {
  const std::filesystem::path file = run / "summary.json";
  const nlohmann::json summary = read_json_object(file);
  BatchRow r;
  r.sequence = sequence;
  try {
    r.frames = summary.at("frames").get<std::size_t>();
    r.keyframes = summary.at("keyframes").get<std::size_t>();
    r.gaussians = summary.at("gaussians").get<std::size_t>();
    r.seconds = summary.at("seconds").get<double>();
    r.fps = static_cast<double>(r.frames) / std::max(r.seconds, 1e-9);
    r.peak_memory_mib = summary.at("peak_memory_mib").get<double>();
  } catch (const nlohmann::json::exception& e) {
    throw splat::Error(file.string() + ": " + e.what());
  }
  return r;
}

std::string batch_markdown(const std::vector<BatchRow>& rows) {
  std::string md =
      "| sequence | frames | keyframes | Gaussians | seconds | frames/s | peak memory (MiB) |\n"
      "|---|---|---|---|---|---|---|\n";
  const auto line = [&](const BatchRow& r, bool bold) {
    if (r.status != "ok") {
      md += "| " + r.sequence + " | " + r.status + ": " + r.error + " | | | | | |\n";
      return;
    }
    const std::string b = bold ? "**" : "";
    char figures[160];
    std::snprintf(figures, sizeof figures, "%zu | %zu | %zu | %.1f | %.2f | %.0f", r.frames,
                  r.keyframes, r.gaussians, r.seconds, r.fps, r.peak_memory_mib);
    md += "| " + b + r.sequence + b + " | " + figures + " |\n";
  };
  for (const BatchRow& r : rows) line(r, false);
  if (const auto total = batch_total(rows)) line(*total, true);
  return md;
}

nlohmann::json batch_json(const std::vector<BatchRow>& rows) {
  nlohmann::json sequences = nlohmann::json::array();
  for (const BatchRow& r : rows) sequences.push_back(row_json(r));
  const auto total = batch_total(rows);
  return {{"sequences", sequences}, {"total", total ? row_json(*total) : nlohmann::json()}};
}

}  // namespace app
