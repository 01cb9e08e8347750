// Reading the JSON files runs leave (summary.json, eval.json, plan.json).
#pragma once
#include <filesystem>

#include <nlohmann/json.hpp>

namespace app {

// The file's JSON; null if it is missing or not JSON (a run that never wrote it, or was killed
// while it did).
nlohmann::json read_json_or_null(const std::filesystem::path& path);

// The file's JSON object. Throws splat::Error naming the file if it cannot be opened or holds no
// JSON object.
nlohmann::json read_json_object(const std::filesystem::path& path);

}  // namespace app
