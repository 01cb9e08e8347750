#include "batch/sequence_finder.h"

#include <algorithm>
#include <set>

#include "datasets/bag_reader.h"
#include "splat/error.h"

namespace app {
namespace {

bool has_images(const std::filesystem::path& dir) {
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    if (e.is_regular_file(ec)) return true;
  }
  return false;
}

// The layouts open_dataset() detects, by the files that mark them.
bool looks_like_sequence(const std::filesystem::path& dir) {
  const auto is = [&](const char* name) { return std::filesystem::exists(dir / name); };
  if (is("rgb.txt") && is("depth.txt")) return true;                                  // TUM, plain folder
  if (is("traj.txt") && std::filesystem::is_directory(dir / "results")) return true;  // Replica
  return std::filesystem::is_directory(dir / "rgb") && std::filesystem::is_directory(dir / "depth") &&
         is("intrinsics.txt") && has_images(dir / "rgb");                             // images
}

void add(const std::filesystem::path& root, const std::filesystem::path& sequence, std::vector<FoundSequence>& found) {
  std::string name = sequence.lexically_relative(root).generic_string();  // the link's name, not its target's
  if (name == ".") name = std::filesystem::absolute(root).lexically_normal().filename().string();  // the root itself
  if (name.empty()) name = "sequence";
  std::replace(name.begin(), name.end(), '/', '_');
  found.push_back({name, sequence});
}

// Symbolic links are followed (a folder of links to datasets is a suite); `visited` holds the
// folders already searched, by their canonical path, so a link back up the tree ends there and a
// sequence linked twice is run once.
void search(const std::filesystem::path& root, const std::filesystem::path& dir, int depth_left,
            std::set<std::filesystem::path>& visited, std::vector<FoundSequence>& found) {
  std::error_code ec;
  const std::filesystem::path canonical = std::filesystem::canonical(dir, ec);
  if (ec || !visited.insert(canonical).second) return;
  if (looks_like_sequence(dir)) return add(root, dir, found);
  // In name order: of two links to one sequence, the first by name is the one kept.
  std::vector<std::filesystem::directory_entry> entries;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) entries.push_back(e);
  std::sort(entries.begin(), entries.end());
  for (const auto& e : entries) {
    if (e.is_regular_file(ec) && is_bag_file(e.path())) {
      if (visited.insert(std::filesystem::canonical(e.path(), ec)).second) {
        add(root, e.path(), found);  // a ROS recording ("teddy.bag" is named "teddy.bag")
      }
    } else if (depth_left > 0 && e.is_directory(ec)) {
      search(root, e.path(), depth_left - 1, visited, found);
    }
  }
}

}  // namespace

std::vector<FoundSequence> find_sequences(const std::filesystem::path& root, int max_depth) {
  if (!std::filesystem::is_directory(root)) throw splat::Error(root.string() + ": not a folder");
  std::vector<FoundSequence> found;
  std::set<std::filesystem::path> visited;
  search(root, root, max_depth, visited, found);
  std::sort(found.begin(), found.end(), [](const FoundSequence& a, const FoundSequence& b) { return a.name < b.name; });
  return found;
}

}  // namespace app
