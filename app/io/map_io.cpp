#include "io/map_io.h"

#include "io/gltf_io.h"
#include "io/ply_io.h"
#include "splat/error.h"

namespace app {

LoadedMap load_map(const std::filesystem::path& path) {
  const std::string ext = path.extension().string();
  LoadedMap out;
  if (ext == ".ply") {
    PlyMap ply = read_ply(path);
    out.gaussians = std::move(ply.gaussians);
    out.labels = std::move(ply.labels);
    if (!ply.skipped_properties.empty()) {
      std::string names;
      for (const auto& name : ply.skipped_properties) names += (names.empty() ? "" : ", ") + name;
      out.notices.push_back(path.string() + ": skipped unknown vertex properties: " + names);
    }
  } else if (ext == ".glb" || ext == ".gltf") {
    GltfSplatScene scene = read_gltf_splats(path);
    out.gaussians = to_gaussians(scene);
    out.labels = to_labels(scene);
    out.notices = std::move(scene.notices);
  } else {
    throw splat::Error(path.string() + ": unknown map format '" + ext + "', expected .ply, .glb or .gltf");
  }
  if (out.gaussians.empty()) throw splat::Error(path.string() + ": the map has no Gaussians");
  return out;
}

void save_map(const std::filesystem::path& path, const splat::Gaussians& gaussians,
              const Eigen::Quaterniond& gltf_from_world, const splat::GaussianLabels* labels) {
  const std::string ext = path.extension().string();
  if (ext == ".ply") return write_ply(path, gaussians, labels);
  if (ext == ".glb" || ext == ".gltf") return write_gltf(path, gaussians, gltf_from_world, labels);
  throw splat::Error(path.string() + ": unknown map format '" + ext + "', expected .ply, .glb or .gltf");
}

}  // namespace app
