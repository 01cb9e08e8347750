#include "support/slurm_cluster.h"

#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <random>
#include <thread>

#include "process/child_process.h"
#include "splat/error.h"

namespace gslam::test {
namespace {

// Daemons start in about a second here; a loaded CI machine gets far more.
constexpr std::chrono::seconds kStartTimeout{120};
// Jobs cancelled at the end get KillWait (5 s below) before SIGKILL, then leave the queue.
constexpr std::chrono::seconds kDrainTimeout{60};
constexpr std::chrono::seconds kExitTimeout{30};
// Polling interval for the events above: short beside them.
constexpr std::chrono::milliseconds kPoll{100};

// Whether child `pid` has exited (reaping it).
bool exited(pid_t pid) { return ::waitpid(pid, nullptr, WNOHANG) != 0; }

std::string last_line_of(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::string line, last;
  while (std::getline(in, line)) {
    if (!line.empty()) last = line;
  }
  return last;
}

}  // namespace

std::unique_ptr<SlurmCluster> SlurmCluster::start(std::string& why_not) {
  if (::geteuid() != 0) {
    why_not = "a test Slurm cluster needs root (slurmd runs jobs as their users)";
    return nullptr;
  }
  for (const char* program :
       {"munged", "slurmctld", "slurmd", "sbatch", "squeue", "scontrol", "scancel", "sinfo"}) {
    if (!program_available(program)) {
      why_not = std::string(program) +
                " is not installed (scripts/install_deps.sh installs slurm-wlm and munge)";
      return nullptr;
    }
  }
  std::unique_ptr<SlurmCluster> cluster(new SlurmCluster());
  why_not = cluster->start_daemons();
  if (!why_not.empty()) return nullptr;  // the destructor stops what did start
  if (!cluster->wait_for_node_idle(why_not)) return nullptr;
  return cluster;
}

std::string SlurmCluster::start_daemons() {
  const std::filesystem::path& d = dir_.path();
  std::filesystem::create_directories(d / "state");
  std::filesystem::create_directories(d / "spool");
  // munge's key: random bytes only root reads, as munged insists.
  {
    std::random_device random;
    std::ofstream key(d / "munge.key", std::ios::binary);
    for (int i = 0; i < 1024; ++i) key.put(static_cast<char>(random() & 0xff));
  }
  ::chmod((d / "munge.key").c_str(), 0400);
  const std::filesystem::path socket = d / "munge.socket";
  const int controller_port = free_loopback_port(), node_port = free_loopback_port();
  if (controller_port == 0 || node_port == 0 || controller_port == node_port)
    return "no free loopback port";
  conf_ = d / "slurm.conf";
  std::ofstream(conf_)
      << "ClusterName=gslamtest\n"
      << "SlurmctldHost=localhost\n"
      << "SlurmctldPort=" << controller_port << "\n"
      << "SlurmdPort=" << node_port << "\n"
      << "AuthType=auth/munge\nAuthInfo=socket=" << socket.string() << "\n"
      << "ProctrackType=proctrack/linuxproc\nTaskPlugin=task/none\n"
      << "SelectType=select/cons_tres\nSelectTypeParameters=CR_CPU\n"
      << "MpiDefault=none\nReturnToService=2\nSlurmUser=root\n"
      << "AccountingStorageType=accounting_storage/none\nJobAcctGatherType=jobacct_gather/none\n"
      << "JobCompType=jobcomp/none\n"
      << "KillWait=5\n"  // a cancelled task's processes get SIGKILL 5 s after SIGTERM
      << "StateSaveLocation=" << (d / "state").string() << "\n"
      << "SlurmdSpoolDir=" << (d / "spool").string() << "\n"
      << "SlurmctldPidFile=" << (d / "slurmctld.pid").string() << "\n"
      << "SlurmdPidFile=" << (d / "slurmd.pid").string() << "\n"
      << "SlurmctldLogFile=" << (d / "slurmctld.log").string() << "\n"
      << "SlurmdLogFile=" << (d / "slurmd.log").string() << "\n"
      << "NodeName=localhost CPUs=" << kCpus << " State=UNKNOWN\n"
      << "PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP\n";
  const std::vector<std::string> env = {"SLURM_CONF=" + conf_.string()};
  struct Daemon {
    std::vector<std::string> args;
    std::string log;
  };
  const std::vector<Daemon> daemons = {
      {{"munged", "--foreground", "--key-file=" + (d / "munge.key").string(),
        "--socket=" + socket.string(), "--pid-file=" + (d / "munged.pid").string(),
        "--log-file=" + (d / "munged.log").string(), "--seed-file=" + (d / "munged.seed").string()},
       "munged.out"},
      {{"slurmctld", "-D", "-c", "-f", conf_.string()}, "slurmctld.out"},
      {{"slurmd", "-D", "-N", "localhost", "-f", conf_.string()}, "slurmd.out"},
  };
  for (const Daemon& daemon : daemons) {
    pid_t pid = -1;
    try {
      pid = app::start_logged(daemon.args, d / daemon.log, env);
    } catch (const splat::Error& e) {
      return e.what();
    }
    daemons_.push_back(pid);
    if (daemon.args[0] == "munged") {
      // slurmctld authenticates through the socket at once: wait for it.
      const auto deadline = std::chrono::steady_clock::now() + kStartTimeout;
      while (!std::filesystem::exists(socket)) {
        if (exited(pid)) {
          daemons_.pop_back();
          return "munged exited: " + last_line_of(d / daemon.log) + " " +
                 last_line_of(d / "munged.log");
        }
        if (std::chrono::steady_clock::now() > deadline) return "munged made no socket in time";
        std::this_thread::sleep_for(kPoll);
      }
    }
  }
  return "";
}

bool SlurmCluster::wait_for_node_idle(std::string& why_not) const {
  const auto deadline = std::chrono::steady_clock::now() + kStartTimeout;
  std::string state;
  while (std::chrono::steady_clock::now() < deadline) {
    state = run("sinfo --noheader --format=%t").output;
    if (state == "idle\n") return true;
    std::this_thread::sleep_for(kPoll);
  }
  why_not = "the node did not become idle (sinfo: '" + state +
            "'; slurmctld.log: " + last_line_of(dir_ / "slurmctld.log") +
            "; slurmd.log: " + last_line_of(dir_ / "slurmd.log") + ")";
  return false;
}

std::string SlurmCluster::command(const std::string& command) const {
  std::string line = "SLURM_CONF=";
  line.append(conf_.string())
      .append(" ")
      .append(command);  // a temp path: no character the shell treats specially
  return line;
}

void SlurmCluster::stop() {
  const bool all_up = daemons_.size() == 3;
  if (all_up) {
    // No job outlives the cluster: slurmstepd would otherwise go on alone.
    run("scancel --full --user=root");
    const auto drained = std::chrono::steady_clock::now() + kDrainTimeout;
    while (std::chrono::steady_clock::now() < drained && !run("squeue --noheader").output.empty()) {
      std::this_thread::sleep_for(kPoll);
    }
    run("scontrol shutdown");
  }
  // munged last: the others authenticate through it until they are down.
  for (auto it = daemons_.rbegin(); it != daemons_.rend(); ++it) {
    const pid_t pid = *it;
    if (!all_up || pid == daemons_.front())
      ::kill(pid, SIGTERM);  // scontrol shutdown stopped the others
    auto deadline = std::chrono::steady_clock::now() + kExitTimeout;
    bool gone = false;
    while (!(gone = exited(pid)) && std::chrono::steady_clock::now() < deadline)
      std::this_thread::sleep_for(kPoll);
    if (!gone) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, nullptr, 0);
    }
  }
  daemons_.clear();
}

SlurmCluster::~SlurmCluster() { stop(); }

}  // namespace gslam::test
