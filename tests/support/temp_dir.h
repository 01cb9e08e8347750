#pragma once
#include <filesystem>
#include <string>

namespace gslam::test {

// A fresh directory under the system temp dir, removed when the object goes away.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

// Writes bytes to a file (for hand-made bad inputs).
void write_text(const std::filesystem::path& path, const std::string& bytes);
// A file's bytes (empty if it cannot be read).
std::string read_text(const std::filesystem::path& path);

}  // namespace gslam::test
