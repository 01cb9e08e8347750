// A JSON file the program wrote (summary.json, eval.json, a table), for the tests to read.
#pragma once
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>

namespace gslam::test {

inline nlohmann::json read_json(const std::filesystem::path& path) {
  std::ifstream in(path);
  return nlohmann::json::parse(in);
}

}  // namespace gslam::test
