#pragma once
#include <filesystem>
#include <string>

#include "commands/backend.h"

namespace app {

struct RenderOptions {
  std::filesystem::path map;
  std::filesystem::path out;
  std::filesystem::path trajectory;  // with intrinsics; otherwise an orbit
  std::string intrinsics;            // fx,fy,cx,cy,W,H
  int orbit = 36;                    // views on the orbit
  std::string size = "640x480";      // orbit image size
  std::string up = "0,0,1";          // orbit axis
  std::string formats = "png";       // comma-separated: png, exr
  std::string background = "0,0,0";  // RGB in [0, 1]
  BackendChoice backend;
};

// `gslam render`: renders a map along a trajectory or an orbit into DIR/view_NNNN.{png,exr}.
// Prints progress and a one-line summary; returns the process exit code. Throws splat::Error.
int run_render(const RenderOptions& options);

}  // namespace app
