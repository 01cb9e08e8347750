// Small generated suites for the tests of gslam benchmark and batch: tiny sequences, a cheap
// configuration, and their tables' rows without the figures that vary run to run.
#pragma once
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "datasets/synthetic_sequence.h"
#include "support/json_file.h"

namespace gslam::test {

// A generated sequence of `frames` frames in `dir`; the seed varies the room.
inline void write_tiny_sequence(const std::filesystem::path& dir, int frames, uint32_t seed = 1) {
  app::SyntheticOptions o;
  o.frames = frames;
  o.seed = seed;
  app::write_synthetic_sequence(dir, o);
}

// SLAM settings that reconstruct a tiny sequence in about a second.
inline std::filesystem::path write_quick_config(const std::filesystem::path& path) {
  std::ofstream(path) << R"({"refine_passes": 1, "mapping": {"iterations": 3}})";
  return path;
}

// A table's rows (benchmark.json or batch.json) without the times and memory, which differ from
// run to run of the same work.
inline nlohmann::json rows_without_timings(const nlohmann::json& table) {
  nlohmann::json rows = table.at("sequences");
  for (nlohmann::json& row : rows) {
    for (const char* varies : {"fps_through", "fps_overall", "fps", "seconds", "peak_memory_mib"})
      row.erase(varies);
  }
  return rows;
}

}  // namespace gslam::test
