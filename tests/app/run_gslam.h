// The gslam executable under test (GSLAM_BINARY is set by CMake for app_tests).
#pragma once
#include <string>

#include "support/run_command.h"

inline gslam::test::RunResult run_gslam(const std::string& args) {
  return gslam::test::run_command(std::string(GSLAM_BINARY) + " " + args);
}
