#include "io/json_file.h"

#include <fstream>

#include "splat/error.h"

namespace app {

nlohmann::json read_json_or_null(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) return nullptr;
  nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  return j.is_discarded() ? nlohmann::json() : j;
}

nlohmann::json read_json_object(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw splat::Error(path.string() + ": cannot open file");
  nlohmann::json j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.is_object()) throw splat::Error(path.string() + ": not a JSON object");
  return j;
}

}  // namespace app
