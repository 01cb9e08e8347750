#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "splat/gaussian_labels.h"
#include "splat/gaussians.h"

namespace app {

struct LoadedMap {
  splat::Gaussians gaussians;
  std::vector<std::string> notices;  // skipped properties, fallbacks taken
  splat::GaussianLabels labels;       // the Gaussians' classes (PLY label_k, glTF _LABEL_k), if the file has them
};

// Loads a map by extension: .ply (INRIA 3DGS) or .glb/.gltf (KHR_gaussian_splatting).
// An empty map is an error naming the file.
LoadedMap load_map(const std::filesystem::path& path);

// Saves a map by extension (.ply, .glb or .gltf), atomically. A glTF file gets `gltf_from_world`
// as its node rotation (write_gltf); a PLY file is written in the world frame regardless.
// `labels` go into either (write_ply, write_gltf).
void save_map(const std::filesystem::path& path, const splat::Gaussians& gaussians,
              const Eigen::Quaterniond& gltf_from_world = Eigen::Quaterniond::Identity(),
              const splat::GaussianLabels* labels = nullptr);

}  // namespace app
