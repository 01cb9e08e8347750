// The table of a batch of reconstructions without ground truth (gslam batch): one row per
// sequence from its run folder's summary.json, and the totals, as Markdown and JSON.
#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace app {

struct BatchRow {
  std::string sequence;
  std::string status = "ok";  // ok, failed, interrupted
  std::string error;          // failed or interrupted: what happened (the log's last line)
  std::size_t frames = 0, keyframes = 0, gaussians = 0;
  double seconds = 0;  // the whole run
  double fps = 0;      // frames / seconds
  double peak_memory_mib = 0;
};

// The row of a finished run folder. Throws splat::Error naming summary.json if it is missing or
// malformed.
BatchRow read_batch_row(const std::string& sequence, const std::filesystem::path& run);

// A Markdown table: a line per row, then the totals over the rows with status ok (frames,
// Gaussians and seconds summed; frames/s over the summed time).
std::string batch_markdown(const std::vector<BatchRow>& rows);
// {"sequences": [{...}, ...], "total": {...} or null}.
nlohmann::json batch_json(const std::vector<BatchRow>& rows);

}  // namespace app
