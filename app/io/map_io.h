#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include "splat/gaussians.h"

namespace app {

struct LoadedMap {
  splat::Gaussians gaussians;
  std::vector<std::string> notices;  // skipped properties, fallbacks taken
};

// Loads a map by extension: .ply (INRIA 3DGS) or .glb/.gltf (KHR_gaussian_splatting).
// An empty map is an error naming the file.
LoadedMap load_map(const std::filesystem::path& path);

// Saves a map by extension (.ply, .glb or .gltf), atomically.
void save_map(const std::filesystem::path& path, const splat::Gaussians& gaussians);

}  // namespace app
