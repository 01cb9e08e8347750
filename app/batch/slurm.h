// Talking to Slurm through its command-line tools (sbatch, squeue), which read SLURM_CONF from
// the environment like any user's: what to pass them and what their output means. Job states
// come from squeue, not sacct, so a cluster without accounting works too.
#pragma once
#include <cstddef>
#include <filesystem>
#include <string>
#include <vector>

namespace app {

// Where and how long each task runs; empty or 0: the cluster's defaults.
struct SlurmOptions {
  std::string partition;
  std::string time_limit;  // sbatch --time: "MINUTES", "HH:MM:SS", "D-HH"...
  int cpus_per_task = 0;
};

// The job id in sbatch's "Submitted batch job 1234" (more lines may come around it). Throws
// splat::Error quoting the output when it holds none.
std::string parse_sbatch_job_id(const std::string& sbatch_output);

// How far an array job has got: squeue lists its pending and running tasks; the rest ended
// (done, failed or cancelled alike, which only the tasks' own results tell apart).
struct ArrayProgress {
  std::size_t pending = 0, running = 0, ended = 0;
};

// The squeue format `squeue_progress` reads: array job id, task id, state, one task a line.
std::vector<std::string> squeue_command();

// The progress of array job `array_job_id` of `tasks` tasks from squeue_command()'s output.
// Tasks still pending before the scheduler split them show as one line with a range
// ("0-3", "0,2,5-7", "0-9%2"), counted in full.
ArrayProgress squeue_progress(const std::string& squeue_output, const std::string& array_job_id,
                              std::size_t tasks);

// Whether job `job_id` (not an array) still appears in squeue_command()'s output.
bool squeue_lists_job(const std::string& squeue_output, const std::string& job_id);

// The sbatch command that submits `script` as tasks 0..tasks-1 of an array job (or one job,
// tasks == 0), named `name`, its output to `log` (%a: the task index), after job
// `after_job` has ended in any state if it is not empty.
std::vector<std::string> sbatch_command(const SlurmOptions& options, const std::string& name,
                                        const std::string& script, const std::string& log,
                                        std::size_t tasks, const std::string& after_job = "");

// The last line slurmstepd wrote into a job's output file `log` ("slurmstepd: error: *** JOB 12
// ON node CANCELLED AT ... ***", or DUE TO TIME LIMIT, or an out-of-memory kill): why Slurm
// ended the task. "" if none.
std::string slurmstepd_error(const std::filesystem::path& log);

// `text` as one shell word (single quotes), for the job scripts.
std::string shell_quote(const std::string& text);

}  // namespace app
