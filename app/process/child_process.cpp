#include "process/child_process.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

#include "splat/error.h"

extern char** environ;

namespace app {
namespace {

// Spawns `args` with `actions` applied to its file descriptors (posix_spawnp: PATH lookup), in
// this process's environment with `environment` before it.
pid_t spawn(const std::vector<std::string>& args, posix_spawn_file_actions_t& actions,
            const std::vector<std::string>& environment = {}) {
  if (args.empty()) throw splat::Error("spawn: no program given");
  std::vector<char*> argv, envp;
  for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  for (const std::string& e : environment) envp.push_back(const_cast<char*>(e.c_str()));
  for (char** e = environ; *e; ++e) envp.push_back(*e);
  envp.push_back(nullptr);
  pid_t pid = 0;
  const int failed = posix_spawnp(&pid, argv[0], &actions, nullptr, argv.data(), envp.data());
  posix_spawn_file_actions_destroy(&actions);
  if (failed != 0) throw splat::Error(args[0] + ": cannot start: " + std::strerror(failed));
  return pid;
}

// spawn with standard output and error appended to `log`, standard input read from `input`
// (-1: /dev/null).
pid_t spawn_logged(const std::vector<std::string>& args, const std::filesystem::path& log, int input,
                   const std::vector<std::string>& environment = {}) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (input < 0) {
    posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  } else {
    posix_spawn_file_actions_adddup2(&actions, input, STDIN_FILENO);  // dup2 clears close-on-exec
  }
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  return spawn(args, actions, environment);
}

int exit_code_of(int status) {
  return WIFSIGNALED(status) ? 128 + WTERMSIG(status) : WEXITSTATUS(status);
}

}  // namespace

std::filesystem::path this_executable() { return std::filesystem::read_symlink("/proc/self/exe"); }

pid_t start_logged(const std::vector<std::string>& args, const std::filesystem::path& log,
                   const std::vector<std::string>& environment) {
  return spawn_logged(args, log, -1, environment);
}

PipedChild start_piped(const std::vector<std::string>& args, const std::filesystem::path& log) {
  int fds[2];
  if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds) != 0) {
    throw splat::Error(std::string("socketpair: ") + std::strerror(errno));
  }
  PipedChild child;
  try {
    child.pid = spawn_logged(args, log, fds[1]);
  } catch (...) {
    close(fds[0]);
    close(fds[1]);
    throw;
  }
  close(fds[1]);
  child.input = fds[0];
  return child;
}

bool write_to_child(const PipedChild& child, std::span<const std::uint8_t> bytes) {
  while (!bytes.empty()) {
    const ssize_t n = send(child.input, bytes.data(), bytes.size(), MSG_NOSIGNAL);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    bytes = bytes.subspan(static_cast<std::size_t>(n));
  }
  return true;
}

int wait_for_child(pid_t pid) {
  int status = 0;
  while (waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR)
      throw splat::Error("lost child process " + std::to_string(pid) + ": " + std::strerror(errno));
  }
  return exit_code_of(status);
}

EndedChild wait_for_any_child() {
  int status = 0;
  pid_t pid = 0;
  while ((pid = waitpid(-1, &status, 0)) < 0) {
    if (errno != EINTR)
      throw splat::Error(std::string("waiting for a child process: ") + std::strerror(errno));
  }
  return {pid, exit_code_of(status)};
}

int run_logged(const std::vector<std::string>& args, const std::filesystem::path& log) {
  return wait_for_child(start_logged(args, log));
}

CapturedRun run_captured(const std::vector<std::string>& args) {
  int fds[2];
  if (pipe2(fds, O_CLOEXEC) != 0) throw splat::Error(std::string("pipe: ") + std::strerror(errno));
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, fds[1], STDOUT_FILENO);
  posix_spawn_file_actions_adddup2(&actions, fds[1], STDERR_FILENO);
  pid_t pid = 0;
  try {
    pid = spawn(args, actions);
  } catch (...) {
    close(fds[0]);
    close(fds[1]);
    throw;
  }
  close(fds[1]);
  CapturedRun r;
  std::array<char, 4096> buffer;
  for (;;) {
    const ssize_t n = read(fds[0], buffer.data(), buffer.size());
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) break;
    r.output.append(buffer.data(), static_cast<std::size_t>(n));
  }
  close(fds[0]);
  r.exit_code = wait_for_child(pid);
  return r;
}

bool program_on_path(const std::string& program) {
  const char* path = std::getenv("PATH");
  std::istringstream dirs(path ? path : "");
  for (std::string dir; std::getline(dirs, dir, ':');) {
    const std::filesystem::path candidate =
        std::filesystem::path(dir.empty() ? "." : dir) / program;
    if (access(candidate.c_str(), X_OK) == 0 && !std::filesystem::is_directory(candidate))
      return true;
  }
  return false;
}

std::string last_line(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::string line, last;
  while (std::getline(in, line)) {
    const std::size_t cr = line.rfind('\r');  // progress lines rewritten on a terminal
    if (cr != std::string::npos) line = line.substr(cr + 1);
    if (line.find_first_not_of(" \t") != std::string::npos) last = line;
  }
  return last;
}

}  // namespace app
