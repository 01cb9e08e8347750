#pragma once
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

namespace gslam::test {

// ../shared/data beside the checkout (third-party data, never committed).
std::filesystem::path shared_data_dir();

// Path of a file under shared data, or an empty path if it is absent.
std::filesystem::path shared_data(const std::string& relative);

}  // namespace gslam::test

// Skips the current test with a clear message when a shared data file is absent.
#define GSLAM_REQUIRE_SHARED_DATA(var, relative)                                        \
  const std::filesystem::path var = ::gslam::test::shared_data(relative);               \
  if (var.empty()) {                                                                    \
    GTEST_SKIP() << "shared data " << (relative) << " not found under "                 \
                 << ::gslam::test::shared_data_dir() << " (see DEVELOPERS.md)";         \
  }
