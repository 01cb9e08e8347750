#pragma once
#include <filesystem>
#include <functional>

#include <nlohmann/json.hpp>

namespace app {

// Runs write(tmp) on a temporary path beside `path`, then renames it over `path`, so readers
// see the old file or the complete new one, never a partial one. The temporary is removed if
// write throws.
void write_atomically(const std::filesystem::path& path,
                      const std::function<void(const std::filesystem::path& tmp)>& write);

// JSON written atomically (pretty-printed); throws splat::Error naming the file if writing fails.
void write_json(const std::filesystem::path& path, const nlohmann::json& j);

}  // namespace app
