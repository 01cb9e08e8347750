#include "support/run_command.h"

#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
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

InterruptedRun run_and_interrupt(const std::string& command, const std::string& event, double timeout_s) {
  InterruptedRun r;
  int fds[2];
  if (::pipe(fds) != 0) return r;
  const pid_t pid = ::fork();
  if (pid < 0) return r;
  if (pid == 0) {  // the child: its own process group, output into the pipe
    ::setpgid(0, 0);
    ::dup2(fds[1], STDOUT_FILENO);
    ::dup2(fds[1], STDERR_FILENO);
    ::close(fds[0]);
    ::close(fds[1]);
    // exec: the shell becomes the program, which alone decides what SIGINT does.
    ::execl("/bin/sh", "sh", "-c", ("exec " + command).c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  ::setpgid(pid, pid);  // also here, so the group exists before any kill below
  ::close(fds[1]);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  bool interrupted = false;
  std::array<char, 4096> buf;
  for (;;) {
    pollfd p{fds[0], POLLIN, 0};
    const int ready = ::poll(&p, 1, 100);
    if (ready > 0) {
      const ssize_t n = ::read(fds[0], buf.data(), buf.size());
      if (n <= 0) break;  // the program and everything it started closed their output
      r.output.append(buf.data(), static_cast<std::size_t>(n));
    }
    if (!interrupted) {
      r.event_seen = r.output.find(event) != std::string::npos;
      if (r.event_seen || std::chrono::steady_clock::now() > deadline) {
        ::kill(-pid, SIGINT);
        interrupted = true;
      }
    }
  }
  ::close(fds[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);
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

int free_loopback_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t size = sizeof address;
  int port = 0;
  if (::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0 &&
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &size) == 0) {
    port = ntohs(address.sin_port);
  }
  ::close(fd);
  return port;
}

}  // namespace gslam::test
