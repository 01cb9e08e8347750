// The plan of a benchmark or batch: its settings, every sequence and which of them still have to
// run. Written to OUT/plan.json, so that a task started elsewhere (a Slurm array task, a local
// --jobs child) runs exactly what the command would, and the merge lists exactly its sequences.
#pragma once
#include <filesystem>
#include <vector>

#include <nlohmann/json.hpp>

#include "batch/sequence_finder.h"
#include "commands/benchmark_command.h"

namespace app {

struct RunPlan {
  BenchmarkOptions options;              // paths absolute
  nlohmann::json config;                 // the effective SLAM settings (defaults and --config)
  std::vector<FoundSequence> sequences;  // all of them, sorted by name; paths absolute
  std::vector<std::size_t> to_run;       // the tasks: sequences not finished with these settings
};

// Finds the sequences (a folder, or for batch a text file listing sequence folders, one per
// line, relative to the file) and which have finished. Throws splat::Error for no sequence, a
// listed folder that is not one, two sequences of one name, or a bad config file.
RunPlan make_run_plan(const BenchmarkOptions& options);

// Writes OUT/plan.json and removes what tasks of an earlier plan left: the outcome files of the
// sequences to run, the tasks' logs and the tables.
void write_run_plan(const RunPlan& plan);
RunPlan read_run_plan(const std::filesystem::path& out);  // throws splat::Error

// Whether sequence `index`'s run folder holds a finished run (evaluated, for a benchmark) with
// the plan's settings.
bool finished_with_plan(const RunPlan& plan, std::size_t index);

// Where sequence `index`'s run goes, its commands' log, and its result file ({"status",
// "error"}, written when its task ends by itself; absent when it was killed or cancelled).
std::filesystem::path run_folder(const RunPlan& plan, std::size_t index);
std::filesystem::path sequence_log(const RunPlan& plan, std::size_t index);
std::filesystem::path outcome_file(const RunPlan& plan, std::size_t index);
// The log of task `task` itself (its progress; Slurm's word on a cancelled or killed task).
std::filesystem::path task_log(const std::filesystem::path& out, std::size_t task);

}  // namespace app
