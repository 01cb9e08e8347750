// Shared by the libFuzzer targets: the readers take paths, so each input is written to a file in
// a per-process folder first (under TMPDIR, which scripts/fuzz.sh points into the build and
// removes after each target). A splat::Error is the expected answer to bad input; anything else
// (a crash, a sanitizer report, another exception) is a finding.
#pragma once
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace gslam::fuzz {

inline std::filesystem::path folder() {
  static const std::filesystem::path dir = [] {
    const auto d = std::filesystem::temp_directory_path() / ("gslam-fuzz-" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    return d;
  }();
  return dir;
}

// Writes the input as `name` in the folder and returns its path.
inline std::filesystem::path write_input(const std::string& name, const uint8_t* data, std::size_t size) {
  const std::filesystem::path path = folder() / name;
  std::filesystem::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return path;
}

}  // namespace gslam::fuzz
