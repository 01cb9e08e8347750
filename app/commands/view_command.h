#pragma once
#include <filesystem>
#include <optional>
#include <vector>

#include "commands/backend.h"

namespace app {

struct ViewOptions {
  std::filesystem::path path;  // a map file (.ply, .glb, .gltf), or a reconstruct/live run folder
  std::filesystem::path screenshot;  // save the first frame drawn to this PNG and exit
  std::optional<int> camera;         // start at this recorded camera (0-based, a trajectory line)
  std::vector<double> up;            // x,y,z; empty: estimated from the cameras, else +z
  BackendChoice backend;
};

// `gslam view`: a window on a finished map (map_view.h). A run folder gives its map.ply, its
// cameras (trajectory.txt, camera to world) and their intrinsics (summary.json), and the up
// direction from the cameras and the floor (estimate_world_up); a map file alone is seen about
// +z unless `up` says otherwise. Mouse: left drag orbits, right or middle (or shift + left) drag
// pans, the wheel zooms; keys: W/A/S/D fly forward/left/back/right, R/F (PageUp/PageDown) up/down
// (shift: 4x), n/p (Right/Left) step through the recorded cameras (shift: 10 at a time), Home or
// 0 returns to the overview, q or Esc quits. Returns the exit code; throws splat::Error for a
// missing or malformed input, a camera out of range, or no display.
int run_view(const ViewOptions& options);

}  // namespace app
