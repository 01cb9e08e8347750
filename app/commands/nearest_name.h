// "Did you mean ...?" for a mistyped command or option name.
#pragma once
#include <optional>
#include <string>
#include <vector>

namespace app {

// The name in `names` closest to `typed` by edit distance (insertions, deletions, substitutions
// and swaps of neighbours), if it is close enough to be the likely intent: at most a third of
// the longer name's length, and at least 1 for short names. Ties go to the earlier name.
std::optional<std::string> nearest_name(const std::string& typed, const std::vector<std::string>& names);

}  // namespace app
