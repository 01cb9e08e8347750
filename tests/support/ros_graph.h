// A real ROS 1 graph for the tests of gslam_ros: roscore on a free loopback port, with its home
// and logs in a temporary folder, and the processes a test starts in it (the node, rosbag play,
// rostopic echo). Each process gets a session of its own; the destructor interrupts them (SIGINT,
// as Ctrl-C), waits, kills what is left, and stops roscore last: no process stays behind.
#pragma once
#include <sys/types.h>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "support/run_command.h"
#include "support/temp_dir.h"

namespace gslam::test {

class RosGraph {
 public:
  // Starts roscore and waits until its master answers. Returns nullptr and sets `why_not` where
  // that cannot be done (roscore not installed, no free port, a master that never answers).
  static std::unique_ptr<RosGraph> start(std::string& why_not);
  ~RosGraph();
  RosGraph(const RosGraph&) = delete;
  RosGraph& operator=(const RosGraph&) = delete;

  // Starts `args` in this graph, its output in dir()/`log`; does not wait.
  pid_t spawn(const std::vector<std::string>& args, const std::string& log);
  // SIGINT to a process started above, then its exit code (128 + signal if a signal ended it).
  int interrupt(pid_t pid);
  // Waits for a process started above to exit by itself; its exit code (a hung one is stopped
  // after 4 minutes).
  int wait(pid_t pid);
  // Runs a shell command in this graph (rosparam, rosservice, rostopic) and collects its output.
  RunResult run(const std::string& command) const;
  const std::filesystem::path& dir() const { return dir_.path(); }

 private:
  RosGraph() = default;
  std::vector<std::string> environment() const;
  void forget(pid_t pid);

  TempDir dir_;
  int port_ = 0;
  pid_t roscore_ = -1;
  std::vector<pid_t> processes_;
};

}  // namespace gslam::test
