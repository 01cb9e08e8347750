// Running a program as a child process with its output in a log file (gslam benchmark runs
// each sequence's reconstruct and eval so, each with its own memory and failure).
#pragma once
#include <filesystem>
#include <string>
#include <vector>

namespace app {

// The running gslam executable (/proc/self/exe).
std::filesystem::path this_executable();

// Runs `args` (args[0] the program) with standard input closed and standard output and error
// appended to `log`; waits for it. Returns its exit code, or 128 + the signal that ended it.
// Throws splat::Error if it cannot be started.
int run_logged(const std::vector<std::string>& args, const std::filesystem::path& log);

// The last non-empty line of a text file (a failed child's error), "" if none.
std::string last_line(const std::filesystem::path& file);

}  // namespace app
