#pragma once
#include <string>

namespace gslam::test {

struct RunResult {
  int exit_code = -1;
  std::string output;  // stdout and stderr together
};

// Runs a shell command and collects its output and exit code.
RunResult run_command(const std::string& command);

// Runs a shell command, and once its output (stdout and stderr) contains `event`, sends SIGINT
// to its process group, as Ctrl-C in a terminal would; then collects the rest of its output and
// its exit code. The interrupt follows what the program did, not a clock; if the event never
// comes within `timeout_s` (a hung program), it is interrupted then and `event_seen` is false.
struct InterruptedRun : RunResult {
  bool event_seen = false;
};
InterruptedRun run_and_interrupt(const std::string& command, const std::string& event, double timeout_s = 900);

// A TCP port on the loopback nobody listens on now (the kernel's pick); 0 if none.
int free_loopback_port();

// Whether a program is on PATH.
bool program_available(const std::string& name);

// How much slower than a plain build this one runs (GSLAM_TEST_TIME_SCALE, default 1; the
// sanitized build sets it), for tests that replay a camera in real time: they replay that much
// slower, so that what they assert holds at the same load. The command-line form of a replay
// speed scaled by it.
double test_time_scale();
std::string replay_speed(double speed);

}  // namespace gslam::test
