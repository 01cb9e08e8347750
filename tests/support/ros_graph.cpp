#include "support/ros_graph.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <thread>

#include "process/child_process.h"
#include "splat/error.h"

namespace gslam::test {
namespace {

// roscore starts in a second or two here; a loaded CI machine gets far more.
constexpr std::chrono::seconds kStartTimeout{120};
constexpr std::chrono::seconds kExitTimeout{60};
// A process that should end by itself (rosbag play) and has not by then hangs: it is stopped,
// well before ctest's limit (600 s), so that the test fails with its message.
constexpr std::chrono::seconds kHangTimeout{240};
constexpr std::chrono::milliseconds kPoll{100};

bool accepts_connections(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(static_cast<uint16_t>(port));
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  const bool ok = ::connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0;
  ::close(fd);
  return ok;
}

// The exit code of `pid` once it exits within `timeout`; -1 if it is still running.
int wait_until(pid_t pid, std::chrono::steady_clock::duration timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  while (true) {
    int status = 0;
    const pid_t r = ::waitpid(pid, &status, WNOHANG);
    if (r == pid) return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    if (r < 0) return -1;
    if (std::chrono::steady_clock::now() > deadline) return -1;
    std::this_thread::sleep_for(kPoll);
  }
}

// SIGINT to the process's session (its children too), then SIGKILL if it does not exit.
int stop(pid_t pid) {
  ::kill(-pid, SIGINT);
  int code = wait_until(pid, kExitTimeout);
  if (code < 0) {
    ::kill(-pid, SIGKILL);
    int status = 0;
    ::waitpid(pid, &status, 0);
    code = 128 + SIGKILL;
  }
  return code;
}

}  // namespace

std::unique_ptr<RosGraph> RosGraph::start(std::string& why_not) {
  if (!program_available("roscore") || !program_available("rosbag")) {
    why_not = "ROS 1 tools not installed (scripts/install_deps.sh installs ros-core)";
    return nullptr;
  }
  std::unique_ptr<RosGraph> graph(new RosGraph());
  graph->port_ = free_loopback_port();
  if (graph->port_ == 0) {
    why_not = "no free loopback port";
    return nullptr;
  }
  graph->roscore_ = graph->spawn({"roscore", "-p", std::to_string(graph->port_)}, "roscore.log");
  graph->forget(graph->roscore_);  // stopped last, by the destructor
  const auto deadline = std::chrono::steady_clock::now() + kStartTimeout;
  // The master answers once rosout has registered with it (roscore starts rosout after it).
  while (!accepts_connections(graph->port_) || graph->run("rosnode list").output.find("/rosout") == std::string::npos) {
    if (std::chrono::steady_clock::now() > deadline) {
      why_not = "roscore did not come up on port " + std::to_string(graph->port_);
      return nullptr;
    }
    std::this_thread::sleep_for(kPoll);
  }
  return graph;
}

RosGraph::~RosGraph() {
  for (auto it = processes_.rbegin(); it != processes_.rend(); ++it) stop(*it);
  if (roscore_ > 0) stop(roscore_);
}

std::vector<std::string> RosGraph::environment() const {
  return {"ROS_MASTER_URI=http://127.0.0.1:" + std::to_string(port_), "ROS_IP=127.0.0.1", "ROS_HOSTNAME=127.0.0.1",
          "ROS_HOME=" + (dir() / "ros_home").string(), "ROS_LOG_DIR=" + (dir() / "ros_log").string()};
}

pid_t RosGraph::spawn(const std::vector<std::string>& args, const std::string& log) {
  // setsid: a session of its own, so that stop() reaches the children (roscore's rosmaster).
  std::vector<std::string> command = {"setsid"};
  command.insert(command.end(), args.begin(), args.end());
  const pid_t pid = app::start_logged(command, dir() / log, environment());
  processes_.push_back(pid);
  return pid;
}

int RosGraph::interrupt(pid_t pid) {
  forget(pid);
  return stop(pid);
}

int RosGraph::wait(pid_t pid) {
  forget(pid);
  const int code = wait_until(pid, kHangTimeout);
  return code >= 0 ? code : stop(pid);
}

RunResult RosGraph::run(const std::string& command) const {
  std::string line;
  for (const std::string& e : environment()) line += e + " ";
  return run_command(line + command);
}

void RosGraph::forget(pid_t pid) { processes_.erase(std::remove(processes_.begin(), processes_.end(), pid), processes_.end()); }

}  // namespace gslam::test
