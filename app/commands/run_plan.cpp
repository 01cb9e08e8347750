#include "commands/run_plan.h"

#include <algorithm>
#include <fstream>
#include <set>

#include "io/atomic_file.h"
#include "io/json_file.h"
#include "io/run_folder.h"
#include "io/slam_config_io.h"
#include "splat/error.h"

namespace app {
namespace {

std::filesystem::path absolute_or_empty(const std::filesystem::path& p) {
  return p.empty() ? p : std::filesystem::absolute(p).lexically_normal();
}

// The sequence folders a list file names, one a line; blank lines and # comments skipped.
std::vector<FoundSequence> listed_sequences(const std::filesystem::path& list) {
  std::ifstream in(list);
  if (!in) throw splat::Error(list.string() + ": cannot open file");
  std::vector<FoundSequence> found;
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    const std::size_t first = line.find_first_not_of(" \t\r"),
                      last = line.find_last_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    const std::filesystem::path dir =
        (list.parent_path() / line.substr(first, last - first + 1)).lexically_normal();
    const std::vector<FoundSequence> here =
        std::filesystem::is_directory(dir) ? find_sequences(dir, 0) : std::vector<FoundSequence>();
    if (here.empty()) {
      throw splat::Error(list.string() + " line " + std::to_string(number) + ": " + dir.string() +
                         " is not a sequence folder");
    }
    found.push_back(here.front());
  }
  std::sort(found.begin(), found.end(),
            [](const FoundSequence& a, const FoundSequence& b) { return a.name < b.name; });
  return found;
}

nlohmann::json options_json(const BenchmarkOptions& o) {
  return {{"evaluate", o.evaluate},
          {"root", o.root},
          {"out", o.out},
          {"config_file", o.config},
          {"test_every", o.test_every},
          {"max_frames", o.max_frames},
          {"baseline", o.baseline},
          {"backend", o.backend.backend},
          {"device", o.backend.device},
          {"threads", o.backend.threads}};
}

BenchmarkOptions options_from_json(const nlohmann::json& j) {
  BenchmarkOptions o;
  o.evaluate = j.at("evaluate").get<bool>();
  o.root = j.at("root").get<std::string>();
  o.out = j.at("out").get<std::string>();
  o.config = j.at("config_file").get<std::string>();
  o.test_every = j.at("test_every").get<int>();
  o.max_frames = j.at("max_frames").get<int>();
  o.baseline = j.at("baseline").get<bool>();
  o.backend.backend = j.at("backend").get<std::string>();
  o.backend.device = j.at("device").get<int>();
  o.backend.threads = j.at("threads").get<int>();
  return o;
}

}  // namespace

RunPlan make_run_plan(const BenchmarkOptions& options) {
  RunPlan plan;
  plan.options = options;
  plan.options.root = absolute_or_empty(options.root);
  plan.options.out = absolute_or_empty(options.out);
  plan.options.config = absolute_or_empty(options.config);
  const std::filesystem::path& root = plan.options.root;
  const bool list = !options.evaluate && std::filesystem::is_regular_file(root);
  plan.sequences = list ? listed_sequences(root) : find_sequences(root);
  if (plan.sequences.empty()) {
    throw splat::Error(root.string() +
                       ": no sequence found below it (TUM or plain rgb.txt + depth.txt, Replica "
                       "results/ + traj.txt, or rgb/ + depth/ + intrinsics.txt folders)");
  }
  std::set<std::string> names;
  for (FoundSequence& s : plan.sequences) {
    s.path = absolute_or_empty(s.path);
    if (!names.insert(s.name).second) {
      throw splat::Error(root.string() + ": two sequences named '" + s.name +
                         "'; their run folders would collide");
    }
  }
  plan.config =
      slam_config_to_json(load_slam_config(plan.options.config));  // a bad file costs nothing
  for (std::size_t i = 0; i < plan.sequences.size(); ++i) {
    if (!finished_with_plan(plan, i)) plan.to_run.push_back(i);
  }
  return plan;
}

void write_run_plan(const RunPlan& plan) {
  nlohmann::json sequences = nlohmann::json::array();
  for (const FoundSequence& s : plan.sequences)
    sequences.push_back({{"name", s.name}, {"path", s.path}});
  std::filesystem::create_directories(plan.options.out);
  write_json(plan.options.out / "plan.json", {{"options", options_json(plan.options)},
                                              {"config", plan.config},
                                              {"sequences", sequences},
                                              {"to_run", plan.to_run}});
  const std::filesystem::path& out = plan.options.out;
  for (std::size_t i : plan.to_run) std::filesystem::remove(outcome_file(plan, i));
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(out / "logs", ec)) {
    if (e.path().filename().string().starts_with("task-")) std::filesystem::remove(e.path());
  }
  for (const char* table : {"benchmark.md", "benchmark.json", "batch.md", "batch.json"})
    std::filesystem::remove(out / table);
}

RunPlan read_run_plan(const std::filesystem::path& out) {
  const std::filesystem::path file = out / "plan.json";
  const nlohmann::json j = read_json_or_null(file);
  if (!j.is_object())
    throw splat::Error(file.string() + ": missing or not JSON (written by gslam benchmark/batch)");
  try {
    RunPlan plan;
    plan.options = options_from_json(j.at("options"));
    plan.config = j.at("config");
    for (const nlohmann::json& s : j.at("sequences")) {
      plan.sequences.push_back({s.at("name").get<std::string>(), s.at("path").get<std::string>()});
    }
    plan.to_run = j.at("to_run").get<std::vector<std::size_t>>();
    for (std::size_t i : plan.to_run) {
      if (i >= plan.sequences.size())
        throw splat::Error(file.string() + ": task of sequence " + std::to_string(i) +
                           " out of range");
    }
    return plan;
  } catch (const nlohmann::json::exception& e) {
    throw splat::Error(file.string() + ": " + e.what());
  }
}

bool finished_with_plan(const RunPlan& plan, std::size_t index) {
  const std::filesystem::path run = run_folder(plan, index);
  const BenchmarkOptions& o = plan.options;
  const nlohmann::json summary = read_json_or_null(run / "summary.json");
  if (!summary.is_object() || !summary.value("complete", false) || !summary.contains("input"))
    return false;
  if (o.evaluate && !std::filesystem::exists(run / "eval.json")) return false;
  const nlohmann::json& input = summary["input"];
  if (input.value("dataset", "") != plan.sequences[index].path.string() ||
      input.value("test_every", -1) != o.test_every ||
      input.value("max_frames", -1) != o.max_frames ||
      input.value("config", nlohmann::json()) != plan.config) {
    return false;
  }
  try {
    check_run_manifest(run, summary);
  } catch (const splat::Error&) {
    return false;
  }
  return !o.evaluate || std::filesystem::last_write_time(run / "eval.json") >=
                            std::filesystem::last_write_time(run / "summary.json");
}

std::filesystem::path run_folder(const RunPlan& plan, std::size_t index) {
  return plan.options.out / plan.sequences[index].name;
}

std::filesystem::path sequence_log(const RunPlan& plan, std::size_t index) {
  return plan.options.out / "logs" / (plan.sequences[index].name + ".log");
}

std::filesystem::path outcome_file(const RunPlan& plan, std::size_t index) {
  return plan.options.out / "outcomes" / (plan.sequences[index].name + ".json");
}

std::filesystem::path task_log(const std::filesystem::path& out, std::size_t task) {
  return out / "logs" / ("task-" + std::to_string(task) + ".log");
}

}  // namespace app
