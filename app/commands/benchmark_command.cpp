#include "commands/benchmark_command.h"

#include <algorithm>
#include <cstdio>
#include <map>

#include "commands/interrupt.h"
#include "commands/run_plan.h"
#include "commands/sequence_run.h"
#include "commands/slurm_submit.h"
#include "process/child_process.h"
#include "splat/error.h"

namespace app {
namespace {

// One sequence at a time in this process (the children are reconstruct and eval), the table
// rewritten after each.
void run_in_turn(const RunPlan& plan) {
  const InterruptGuard interrupt;
  for (std::size_t t = 0; t < plan.to_run.size() && !InterruptGuard::interrupted(); ++t) {
    const std::size_t i = plan.to_run[t];
    std::fprintf(stderr, "%zu/%zu: %s (%s), log %s\n", t + 1, plan.to_run.size(),
                 plan.sequences[i].name.c_str(), plan.sequences[i].path.c_str(),
                 sequence_log(plan, i).c_str());
    run_planned_sequence(plan, i);
    merge_run_tables(plan);
  }
  if (InterruptGuard::interrupted())
    std::fprintf(stderr, "interrupted; the same command continues\n");
}

// `jobs` tasks at once, each a `gslam benchmark-task` child logged to its task log, as a Slurm
// array task would run it; the table rewritten as each ends.
void run_as_jobs(const RunPlan& plan, int jobs) {
  const InterruptGuard interrupt;  // the children hear Ctrl-C too and end with what they did
  const std::string gslam = this_executable().string();
  std::map<pid_t, std::size_t> running;
  std::size_t next = 0, ended = 0;
  while (next < plan.to_run.size() || !running.empty()) {
    while (running.size() < static_cast<std::size_t>(jobs) && next < plan.to_run.size() &&
           !InterruptGuard::interrupted()) {
      const std::filesystem::path log = task_log(plan.options.out, next);
      running[start_logged(
          {gslam, "benchmark-task", plan.options.out.string(), std::to_string(next)}, log)] = next;
      std::fprintf(stderr, "started %s, log %s\n", plan.sequences[plan.to_run[next]].name.c_str(),
                   log.c_str());
      ++next;
    }
    if (running.empty()) break;
    const EndedChild child = wait_for_any_child();
    const auto task = running.find(child.pid);
    if (task == running.end()) continue;
    const std::size_t i = plan.to_run[task->second];
    running.erase(task);
    std::fprintf(stderr, "%zu/%zu ended: %s%s\n", ++ended, plan.to_run.size(),
                 plan.sequences[i].name.c_str(), child.exit_code == 0 ? "" : " (see its log)");
    merge_run_tables(plan);
  }
  if (InterruptGuard::interrupted())
    std::fprintf(stderr, "interrupted; the same command continues\n");
}

}  // namespace

int run_benchmark(const BenchmarkOptions& options) {
  if (options.jobs < 1)
    throw splat::Error("--jobs must be >= 1, got " + std::to_string(options.jobs));
  if (options.slurm && !program_on_path("sbatch")) {
    throw splat::Error(
        "--slurm: sbatch is not on PATH (install Slurm's client tools, or run without --slurm)");
  }
  refuse_while_jobs_queued(options.out);
  const RunPlan plan = make_run_plan(options);
  write_run_plan(plan);
  std::filesystem::create_directories(plan.options.out / "logs");
  for (std::size_t i = 0; i < plan.sequences.size(); ++i) {
    if (std::find(plan.to_run.begin(), plan.to_run.end(), i) == plan.to_run.end()) {
      std::fprintf(stderr, "%s (%s): finished earlier\n", plan.sequences[i].name.c_str(),
                   plan.sequences[i].path.c_str());
    }
  }
  if (options.slurm && !plan.to_run.empty()) return submit_to_slurm(plan);
  if (options.jobs > 1) {
    run_as_jobs(plan, options.jobs);
  } else {
    run_in_turn(plan);
  }
  return report_table(merge_run_tables(plan), plan);
}

int run_benchmark_task(const std::filesystem::path& out, std::size_t task) {
  const RunPlan plan = read_run_plan(out);
  if (task >= plan.to_run.size()) {
    throw splat::Error("benchmark-task: task " + std::to_string(task) + " of a plan of " +
                       std::to_string(plan.to_run.size()));
  }
  const InterruptGuard interrupt;  // a signal stops the commands, and the outcome is still written
  const std::size_t i = plan.to_run[task];
  std::fprintf(stderr, "task %zu: %s (%s), log %s\n", task, plan.sequences[i].name.c_str(),
               plan.sequences[i].path.c_str(), sequence_log(plan, i).c_str());
  return run_planned_sequence(plan, i) ? 0 : 1;
}

int run_benchmark_merge(const std::filesystem::path& out) {
  const RunPlan plan = read_run_plan(out);
  return report_table(merge_run_tables(plan), plan);
}

}  // namespace app
