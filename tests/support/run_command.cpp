#include "support/run_command.h"

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <cstdlib>

namespace gslam::test {

RunResult run_command(const std::string& command) {
  RunResult r;
  std::FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return r;
  std::array<char, 4096> buf;
  while (std::fgets(buf.data(), buf.size(), pipe)) r.output += buf.data();
  const int status = ::pclose(pipe);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

bool program_available(const std::string& name) {
  return run_command("command -v " + name + " >/dev/null").exit_code == 0;
}

double test_time_scale() {
  const char* text = std::getenv("GSLAM_TEST_TIME_SCALE");
  if (text == nullptr) return 1;
  const double scale = std::atof(text);
  return scale >= 1 ? scale : 1;
}

std::string replay_speed(double speed) {
  char text[64];
  std::snprintf(text, sizeof text, " --speed %.6g", speed / test_time_scale());
  return text;
}

}  // namespace gslam::test
