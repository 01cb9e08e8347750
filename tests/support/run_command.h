#pragma once
#include <string>

namespace gslam::test {

struct RunResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

// Runs a shell command and collects its output and exit code.
RunResult run_command(const std::string& command);

// Whether a program is on PATH.
bool program_available(const std::string& name);

}  // namespace gslam::test
