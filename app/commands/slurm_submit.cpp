#include "commands/slurm_submit.h"

#include <chrono>
#include <cstdio>
#include <fstream>
#include <thread>

#include "batch/slurm.h"
#include "commands/interrupt.h"
#include "commands/sequence_run.h"
#include "io/atomic_file.h"
#include "io/json_file.h"
#include "process/child_process.h"
#include "splat/error.h"

namespace app {
namespace {

// How often squeue is asked: a job's state changes on the scheduler's clock, seconds apart.
constexpr std::chrono::seconds kPollInterval{1};
// squeue failing this many times in a row (the controller gone) ends the wait.
constexpr int kMaxSqueueFailures = 60;

// Writes a job script that runs `gslam ARGS` (the shell adds the array task's index, if `task`).
std::filesystem::path write_job_script(const std::filesystem::path& path,
                                       const std::vector<std::string>& args, bool task) {
  std::filesystem::create_directories(path.parent_path());
  std::ofstream script(path);
  script << "#!/bin/sh\nexec";
  for (const std::string& a : args) script << ' ' << shell_quote(a);
  if (task) script << " \"$SLURM_ARRAY_TASK_ID\"";
  script << '\n';
  if (!script) throw splat::Error(path.string() + ": cannot write the job script");
  std::filesystem::permissions(path, std::filesystem::perms::owner_exec,
                               std::filesystem::perm_options::add);
  return path;
}

std::string submit(const std::vector<std::string>& sbatch) {
  const CapturedRun r = run_captured(sbatch);
  if (r.exit_code != 0) {
    const std::string output = r.output.substr(0, r.output.find_last_not_of("\n") + 1);
    throw splat::Error("sbatch failed (exit code " + std::to_string(r.exit_code) +
                       "): " + output.substr(output.rfind('\n') + 1));
  }
  return parse_sbatch_job_id(r.output);
}

// Polls squeue until the array's tasks and the merge job have left it, printing each change.
// Returns false if interrupted or if squeue kept failing.
bool wait_for_jobs(const std::string& array_job, const std::string& merge_job, std::size_t tasks) {
  const InterruptGuard interrupt;
  std::string shown;
  int failures = 0;
  while (!InterruptGuard::interrupted()) {
    const CapturedRun q = run_captured(squeue_command());
    if (q.exit_code != 0) {
      if (++failures == kMaxSqueueFailures) {
        std::fprintf(stderr, "slurm: squeue keeps failing (%s); not waiting any longer\n",
                     q.output.c_str());
        return false;
      }
    } else {
      failures = 0;
      const ArrayProgress p = squeue_progress(q.output, array_job, tasks);
      const bool merging = squeue_lists_job(q.output, merge_job);
      const std::string line = "slurm: tasks " + std::to_string(p.pending) + " pending, " +
                               std::to_string(p.running) + " running, " + std::to_string(p.ended) +
                               " of " + std::to_string(tasks) + " ended" +
                               (p.ended == tasks && merging ? "; merging" : "");
      if (line != shown) std::fprintf(stderr, "%s\n", (shown = line).c_str());
      if (p.ended == tasks && !merging) return true;
    }
    std::this_thread::sleep_for(kPollInterval);
  }
  return false;
}

}  // namespace

void refuse_while_jobs_queued(const std::filesystem::path& out) {
  const nlohmann::json jobs = read_json_or_null(out / "slurm" / "jobs.json");
  if (!jobs.is_object() || !program_on_path("squeue")) return;
  const CapturedRun q = run_captured(squeue_command());
  if (q.exit_code != 0) return;  // no controller to ask: the jobs cannot be running either
  for (const char* key : {"array_job", "merge_job"}) {
    const std::string job = jobs.value(key, "");
    if (!job.empty() && squeue_lists_job(q.output, job)) {
      throw splat::Error(
          out.string() + ": jobs " + jobs.value("array_job", "") + " and " +
          jobs.value("merge_job", "") +
          " of an earlier --slurm run are still in squeue; wait for them, or scancel them first");
    }
  }
}

int submit_to_slurm(const RunPlan& plan) {
  const std::filesystem::path& out = plan.options.out;
  const std::string gslam = this_executable().string();
  const std::string name = std::string("gslam-") + (plan.options.evaluate ? "benchmark" : "batch");
  const SlurmOptions& slurm = plan.options.slurm_options;
  const std::filesystem::path task_script =
      write_job_script(out / "slurm" / "task.sh", {gslam, "benchmark-task", out}, true);
  const std::filesystem::path merge_script =
      write_job_script(out / "slurm" / "merge.sh", {gslam, "benchmark-merge", out}, false);
  const std::size_t tasks = plan.to_run.size();
  const std::string array_job =
      submit(sbatch_command(slurm, name, task_script, out / "logs" / "task-%a.log", tasks));
  std::string merge_job;
  try {
    merge_job = submit(sbatch_command(slurm, name + "-merge", merge_script,
                                      out / "logs" / "merge.log", 0, array_job));
  } catch (const splat::Error&) {
    run_captured({"scancel", array_job});  // tasks whose table nobody would write
    throw;
  }
  write_json(out / "slurm" / "jobs.json", {{"array_job", array_job}, {"merge_job", merge_job}});
  std::printf("slurm: array job %s (%zu tasks, logs %s), merge job %s (log %s)\n",
              array_job.c_str(), tasks, (out / "logs" / "task-N.log").c_str(), merge_job.c_str(),
              (out / "logs" / "merge.log").c_str());
  std::fflush(stdout);
  const std::filesystem::path table = out / (plan.options.evaluate ? "benchmark" : "batch");
  if (!plan.options.wait) {
    std::fprintf(
        stderr,
        "not waiting: squeue follows the jobs; the table will be %s.md; scancel %s %s stops them\n",
        table.c_str(), array_job.c_str(), merge_job.c_str());
    return 0;
  }
  if (!wait_for_jobs(array_job, merge_job, tasks)) {
    std::fprintf(
        stderr,
        "stopped waiting; the jobs go on (scancel %s %s stops them), the table will be %s.md\n",
        array_job.c_str(), merge_job.c_str(), table.c_str());
    return 1;
  }
  const std::optional<MergedTable> merged = read_merged_table(plan);
  if (!merged)
    throw splat::Error("merge job " + merge_job +
                       " wrote no table: " + last_line(out / "logs" / "merge.log"));
  return report_table(*merged, plan);
}

}  // namespace app
