// A run folder holds one run. Its summary.json carries a manifest: the run's id and, for each
// output file, its size and checksum, so a reader can tell files of another run apart.
#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace app {

// The files a run writes into its folder (relative paths); keyframes/ is owned as a whole.
inline const std::vector<std::string> kRunFiles = {"trajectory.txt", "map.ply", "map.glb", "summary.json",
                                                    "checkpoint.bin",
                                                    "eval.json", "trajectory_top.png", "ate_over_time.png",
                                                    "psnr_over_time.png"};

// Prepares `dir` for a new run: refuses one that holds a run's outputs (naming --overwrite)
// unless `overwrite`, in which case those outputs are removed; temporary files a killed run
// left are removed either way. Throws splat::Error.
void prepare_run_folder(const std::filesystem::path& dir, bool overwrite);

// Removes the temporary files of write_atomically that a killed run left in `dir` and its
// keyframes/ (a resumed run keeps the rest).
void remove_stale_temporaries(const std::filesystem::path& dir);

// {"run_id": id, "files": {"map.ply": {"bytes": n, "fnv1a64": "..."}, ...}} for the files of
// `names` that exist in `dir`.
nlohmann::json run_manifest(const std::filesystem::path& dir, const std::string& run_id,
                            const std::vector<std::filesystem::path>& names);

// Throws splat::Error naming the first file whose size or checksum differs from the manifest in
// `summary` (a file of another run), or that the manifest lists and is missing.
void check_run_manifest(const std::filesystem::path& dir, const nlohmann::json& summary);

// A new run's id: time and process, unique enough to tell runs apart.
std::string new_run_id();

}  // namespace app
