#pragma once
#include <cstdint>
#include <filesystem>

namespace app {

struct SyntheticOptions {
  int frames = 60;
  int width = 320, height = 240;
  double focal = 260;     // pixels; principal point at the image centre
  double fps = 30;
};

// Writes a synthetic RGB-D sequence in TUM layout (rgb/, depth/ as 16-bit PNG / 5000,
// rgb.txt, depth.txt, groundtruth.txt and intrinsics.txt) with exact ground truth. The images
// come from a ray caster of a textured room with spheres and boxes, independent of the splat
// renderer, so reconstruction is never tested on its own image model. Deterministic.
void write_synthetic_sequence(const std::filesystem::path& dir, const SyntheticOptions& options);

}  // namespace app
