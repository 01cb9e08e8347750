// Finding the RGB-D sequences under a folder, for commands that run many (gslam benchmark).
#pragma once
#include <filesystem>
#include <string>
#include <vector>

namespace app {

struct FoundSequence {
  std::string name;  // its path below the root, '/' written '_' ("fr1_desk"); the root itself: its folder name
  std::filesystem::path path;
};

// The folders at or below `root` (at most `max_depth` levels down) that hold a sequence in a
// layout open_dataset() reads, detected by their files (TUM or plain lists, Replica, images),
// and the ROS recordings (.bag, .mcap) in the folders searched; a sequence's own subfolders are
// not searched. Sorted by name. Symbolic links are followed, each folder searched once (a link
// loop ends, a sequence linked twice is found once). Throws splat::Error if `root` is not a folder.
std::vector<FoundSequence> find_sequences(const std::filesystem::path& root, int max_depth = 4);

}  // namespace app
