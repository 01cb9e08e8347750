// Where the image readers read from: a file, or an encoded image in memory (a ROS
// CompressedImage) read through the same FILE* as one (fmemopen).
#pragma once
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <span>
#include <string>

#include "io/file_error.h"

namespace app {

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using ImageSource = std::unique_ptr<std::FILE, FileCloser>;

inline ImageSource open_image_file(const std::filesystem::path& path) {
  ImageSource file(std::fopen(path.c_str(), "rb"));
  if (!file) fail(path, "cannot open file");
  return file;
}

// The bytes must outlive the source; `where` names them in errors.
inline ImageSource open_image_bytes(std::span<const std::uint8_t> bytes, const std::string& where) {
  if (bytes.empty()) fail(where, "image has no bytes");
  ImageSource file(fmemopen(const_cast<std::uint8_t*>(bytes.data()), bytes.size(), "rb"));
  if (!file) fail(where, "cannot read the image's bytes");
  return file;
}

}  // namespace app
