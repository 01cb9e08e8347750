#pragma once
#include <filesystem>
#include <optional>
#include <string>

#include "commands/backend.h"

namespace app {

struct RenderOptions {
  std::filesystem::path map;         // a map file, or a run folder (its map, trajectory and camera)
  std::filesystem::path out;
  std::filesystem::path trajectory;  // with intrinsics: camera poses for the views
  std::string intrinsics;            // fx,fy,cx,cy,W,H
  std::string path;                  // along poses: "recorded" (at them; the default with a
                                     // trajectory given) or "novel" (near them; the default for
                                     // a run folder's own cameras)
  int views = 0;                     // views along a novel path; 0: one per pose
  std::string offset = "0.1,-0.05,0";  // novel path: metres in each camera's axes (right, down, forward)
  std::optional<int> orbit;          // views on an orbit (the default, 36, for a map without poses)
  std::string size = "640x480";      // orbit image size where no camera is known
  std::optional<std::string> up;     // orbit axis; by default from the cameras, else 0,0,1
  std::string formats = "png";       // comma-separated: png, exr, mp4
  double fps = 30;                   // mp4
  std::string background = "0,0,0";  // RGB in [0, 1]
  BackendChoice backend;
  bool overwrite = false;            // replace the views of an earlier render in `out`
  bool labels = false;               // draw the map's classes (a fixed palette) instead of colour
  std::string only;                  // comma-separated classes (names or ids) whose Gaussians are kept
  std::string highlight;             // comma-separated classes drawn in colour, the others grey and dim
};

// `gslam render`: renders a map into DIR/view_NNNN.{png,exr} and/or DIR/render.mp4:
// - along camera poses: exactly at the poses of a --trajectory (with --intrinsics, or a run
//   folder's camera), or for a run folder's own trajectory a smooth path near them
//   (viewer/views.h novel_path); --path chooses either way;
// - or on an orbit: about the centre at the cameras' height with their up where the map has
//   poses, else at 2.5 map radii about --up.
// With `labels`, each view shows the most probable class per pixel (a map with labels: a run of
// a sequence with label images); `only` keeps the Gaussians of the named classes, resolved by
// the run's summary.json (names) or given as ids; `highlight` keeps every Gaussian but draws
// those of other classes grey and dim.
// Refuses an `out` that holds an earlier render's views unless `overwrite` (which removes them).
// Prints the path used, progress and a one-line summary; returns the process exit code. Throws
// splat::Error.
int run_render(const RenderOptions& options);

}  // namespace app
