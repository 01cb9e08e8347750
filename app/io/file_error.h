#pragma once
#include <filesystem>
#include <string>

#include "splat/error.h"

namespace app {

// Throws splat::Error("<path>: <what>"): the one shape of every file error in app.
[[noreturn]] inline void fail(const std::filesystem::path& path, const std::string& what) {
  throw splat::Error(path.string() + ": " + what);
}

}  // namespace app
