#include "batch/slurm.h"

#include <fstream>
#include <regex>
#include <sstream>

#include "splat/error.h"

namespace app {
namespace {

// The number of task indices in a squeue range list: "3", "0-3", "0,2,5-7", "0-9%2" (%: the
// limit on tasks running at once, not an index).
std::size_t count_indices(std::string list) {
  list = list.substr(0, list.find('%'));
  std::size_t count = 0;
  std::istringstream parts(list);
  for (std::string part; std::getline(parts, part, ',');) {
    const std::size_t dash = part.find('-');
    if (dash == std::string::npos) {
      ++count;
    } else {
      const long first = std::stol(part.substr(0, dash)), last = std::stol(part.substr(dash + 1));
      if (last >= first) count += static_cast<std::size_t>(last - first + 1);
    }
  }
  return count;
}

}  // namespace

std::string parse_sbatch_job_id(const std::string& sbatch_output) {
  static const std::regex kSubmitted(R"(Submitted batch job (\d+))");
  std::smatch m;
  if (!std::regex_search(sbatch_output, m, kSubmitted)) {
    throw splat::Error("sbatch: no job id in its output: '" + sbatch_output + "'");
  }
  return m[1].str();
}

std::vector<std::string> squeue_command() {
  return {"squeue", "--noheader", "--array", "--format=%F %K %T"};
}

ArrayProgress squeue_progress(const std::string& squeue_output, const std::string& array_job_id,
                              std::size_t tasks) {
  ArrayProgress p;
  std::istringstream lines(squeue_output);
  for (std::string line; std::getline(lines, line);) {
    std::istringstream fields(line);
    std::string job, task, state;
    if (!(fields >> job >> task >> state) || job != array_job_id) continue;
    std::string indices = task;
    if (indices.size() > 2 && indices.front() == '[' && indices.back() == ']')
      indices = indices.substr(1, indices.size() - 2);
    std::size_t n = 1;
    try {
      n = count_indices(indices);
    } catch (const std::exception&) {
      throw splat::Error("squeue: cannot read the task ids '" + task + "' in line '" + line + "'");
    }
    (state == "PENDING" ? p.pending : p.running) += n;  // running, completing, suspended: not ended
  }
  const std::size_t listed = p.pending + p.running;
  p.ended = tasks > listed ? tasks - listed : 0;
  return p;
}

bool squeue_lists_job(const std::string& squeue_output, const std::string& job_id) {
  std::istringstream lines(squeue_output);
  for (std::string line; std::getline(lines, line);) {
    std::istringstream fields(line);
    std::string job;
    if (fields >> job && job == job_id) return true;
  }
  return false;
}

std::vector<std::string> sbatch_command(const SlurmOptions& o, const std::string& name,
                                        const std::string& script, const std::string& log,
                                        std::size_t tasks, const std::string& after_job) {
  std::vector<std::string> args = {"sbatch", "--job-name=" + name, "--output=" + log};
  if (tasks > 0) args.push_back("--array=0-" + std::to_string(tasks - 1));
  if (!after_job.empty()) args.push_back("--dependency=afterany:" + after_job);
  if (!o.partition.empty()) args.push_back("--partition=" + o.partition);
  if (!o.time_limit.empty()) args.push_back("--time=" + o.time_limit);
  if (o.cpus_per_task > 0) args.push_back("--cpus-per-task=" + std::to_string(o.cpus_per_task));
  args.push_back(script);
  return args;
}

std::string slurmstepd_error(const std::filesystem::path& log) {
  std::ifstream in(log);
  std::string line, found;
  while (std::getline(in, line)) {
    if (line.starts_with("slurmstepd")) found = line;
  }
  return found;
}

std::string shell_quote(const std::string& text) {
  std::string quoted = "'";
  for (char c : text) quoted += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return quoted + "'";
}

}  // namespace app
