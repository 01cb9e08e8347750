// One sequence of a plan, run the same way wherever it runs (the local loop, a --jobs child, a
// Slurm array task), and the merge of the plan's run folders into its table.
#pragma once
#include <filesystem>
#include <optional>
#include <string>

#include "commands/run_plan.h"

namespace app {

// Runs `gslam reconstruct` (resuming an interrupted run) and, for a benchmark, `gslam eval`
// and the OpenCV baseline on sequence `index`, each a child process logged to its
// sequence_log; then writes its outcome_file. Prints a line on how it went. Returns whether it
// finished (false: failed or interrupted). Throws splat::Error if a child cannot be started.
bool run_planned_sequence(const RunPlan& plan, std::size_t index);

struct MergedTable {
  std::string markdown;
  std::size_t failed = 0;  // rows with status failed
  std::filesystem::path markdown_file, json_file;
};

// Reads every sequence's run folder (finished before the plan, or its task's outcome file says
// so), outcome (failed or interrupted by itself) or logs (killed or cancelled: Slurm's
// slurmstepd line, else the task's log's last line, else the sequence log's) into a row, and
// writes OUT/benchmark.md and .json (batch: OUT/batch.md and .json).
MergedTable merge_run_tables(const RunPlan& plan);

// The table merge_run_tables wrote, read back (the merge job's); nullopt if it is not there.
std::optional<MergedTable> read_merged_table(const RunPlan& plan);

// Prints the table to standard output, and where it is and how many sequences failed to
// standard error. Returns the command's exit code: 1 if one failed, else 0.
int report_table(const MergedTable& table, const RunPlan& plan);

}  // namespace app
