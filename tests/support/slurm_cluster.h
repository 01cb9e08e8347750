// A real one-node Slurm cluster in a temporary folder, for the tests of gslam's --slurm path:
// munged with its own key and socket, slurmctld and slurmd (run as root, in the foreground, as
// children of the test) on free loopback ports, no accounting. Commands reach it through
// SLURM_CONF, which command() sets.
#pragma once
#include <sys/types.h>

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "support/run_command.h"
#include "support/temp_dir.h"

namespace gslam::test {

class SlurmCluster {
 public:
  // Starts the daemons and waits until the node is idle. Returns nullptr and sets `why_not`
  // where that cannot be done: not root, Slurm or munge not installed, or a daemon that does not
  // come up (its log's last line).
  static std::unique_ptr<SlurmCluster> start(std::string& why_not);

  // Cancels every job, waits for them to leave the queue, shuts the daemons down and waits for
  // them to exit (killing what is left after a timeout): no process stays behind.
  ~SlurmCluster();
  SlurmCluster(const SlurmCluster&) = delete;
  SlurmCluster& operator=(const SlurmCluster&) = delete;

  // `command` with SLURM_CONF pointing at this cluster (for gslam --slurm, squeue, scancel).
  std::string command(const std::string& command) const;
  RunResult run(const std::string& command) const { return run_command(this->command(command)); }

  // The CPUs of the one node.
  static constexpr int kCpus = 2;

 private:
  SlurmCluster() = default;
  std::string start_daemons();  // "" or why not
  bool wait_for_node_idle(std::string& why_not) const;
  void stop();

  TempDir dir_;
  std::filesystem::path conf_;
  std::vector<pid_t> daemons_;  // munged, slurmctld, slurmd
};

}  // namespace gslam::test
