// gslam benchmark/batch --slurm: the plan's tasks as one Slurm array job, their merge as a job
// after it.
#pragma once
#include "commands/run_plan.h"

namespace app {

// Submits task i of the plan (gslam benchmark-task OUT i) as array task i, and the merge
// (gslam benchmark-merge OUT) as a job that starts once every task has ended, however it ended;
// their output goes to OUT/logs/task-I.log and OUT/logs/merge.log. Prints the job ids. With
// options.wait, follows the tasks through squeue (pending, running, ended), then prints the
// merged table and returns 1 if a sequence failed; else returns 0 at once. The gslam
// executable, the sequences and OUT must be on a filesystem every node sees. Throws
// splat::Error if sbatch refuses a job.
int submit_to_slurm(const RunPlan& plan);

// Throws splat::Error if jobs that an earlier --slurm run submitted for `out` (kept in
// OUT/slurm/jobs.json) are still in squeue: a new plan would pull their files from under them.
// Nothing to check without that file or without squeue.
void refuse_while_jobs_queued(const std::filesystem::path& out);

}  // namespace app
