#include "io/run_folder.h"

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <fstream>

#include "splat/error.h"

namespace app {
namespace {

// FNV-1a over the file's bytes: cheap, and enough to tell two runs' outputs apart.
std::string checksum(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw splat::Error(file.string() + ": cannot open file");
  uint64_t hash = 14695981039346656037ull;
  char buffer[1 << 16];
  while (in.read(buffer, sizeof(buffer)) || in.gcount() > 0) {
    for (std::streamsize i = 0; i < in.gcount(); ++i) {
      hash = (hash ^ static_cast<unsigned char>(buffer[i])) * 1099511628211ull;
    }
  }
  char text[17];
  std::snprintf(text, sizeof(text), "%016llx", static_cast<unsigned long long>(hash));
  return text;
}

// Temporary files of write_atomically: ".name.tmpPID.ext".
void remove_temporaries_in(const std::filesystem::path& dir) {
  if (!std::filesystem::is_directory(dir)) return;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (entry.is_regular_file() && name.size() > 1 && name[0] == '.' && name.find(".tmp") != std::string::npos) {
      std::filesystem::remove(entry.path());
    }
  }
}

}  // namespace

void remove_stale_temporaries(const std::filesystem::path& dir) {
  remove_temporaries_in(dir);
  remove_temporaries_in(dir / "keyframes");
}

void prepare_run_folder(const std::filesystem::path& dir, bool overwrite) {
  std::filesystem::create_directories(dir);
  remove_stale_temporaries(dir);
  std::vector<std::filesystem::path> owned;
  for (const std::string& name : kRunFiles) {
    if (std::filesystem::exists(dir / name)) owned.push_back(dir / name);
  }
  if (std::filesystem::exists(dir / "keyframes")) owned.push_back(dir / "keyframes");
  if (owned.empty()) return;
  if (!overwrite) {
    throw splat::Error(dir.string() + ": holds another run's outputs (" + owned.front().filename().string() +
                       "); give --overwrite to replace them, " +
                       (std::filesystem::exists(dir / "checkpoint.bin") ? "--resume to continue that interrupted run, " : "") +
                       "or another --out");
  }
  for (const auto& path : owned) std::filesystem::remove_all(path);
}

nlohmann::json run_manifest(const std::filesystem::path& dir, const std::string& run_id,
                            const std::vector<std::filesystem::path>& names) {
  nlohmann::json files = nlohmann::json::object();
  for (const auto& name : names) {
    const std::filesystem::path file = dir / name;
    if (!std::filesystem::is_regular_file(file)) continue;
    files[name.generic_string()] = {{"bytes", std::filesystem::file_size(file)}, {"fnv1a64", checksum(file)}};
  }
  return {{"run_id", run_id}, {"files", files}};
}

void check_run_manifest(const std::filesystem::path& dir, const nlohmann::json& summary) {
  if (!summary.is_object() || !summary.contains("manifest")) {
    throw splat::Error((dir / "summary.json").string() + ": no manifest: not a complete run of this version");
  }
  const nlohmann::json& manifest = summary.at("manifest");
  if (!manifest.contains("files") || !manifest.at("files").is_object()) {
    throw splat::Error((dir / "summary.json").string() + ": manifest without files");
  }
  for (const auto& [name, expected] : manifest.at("files").items()) {
    const std::filesystem::path file = dir / name;
    if (!std::filesystem::is_regular_file(file)) throw splat::Error(file.string() + ": listed in the run's manifest but missing");
    const bool same = expected.is_object() && expected.value("bytes", uint64_t{0}) == std::filesystem::file_size(file) &&
                      expected.value("fnv1a64", std::string()) == checksum(file);
    if (!same) {
      throw splat::Error(file.string() + ": not the file run " + manifest.value("run_id", std::string("?")) +
                         " wrote (size or checksum differs): the folder mixes runs");
    }
  }
}

std::string new_run_id() {
  const auto now = std::chrono::system_clock::now().time_since_epoch();
  char text[48];
  std::snprintf(text, sizeof(text), "%llx-%d",
                static_cast<unsigned long long>(std::chrono::duration_cast<std::chrono::microseconds>(now).count()),
                static_cast<int>(::getpid()));
  return text;
}

}  // namespace app
