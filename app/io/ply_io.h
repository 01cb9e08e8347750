#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include "splat/gaussian_labels.h"
#include "splat/gaussians.h"

namespace app {

struct PlyMap {
  splat::Gaussians gaussians;
  std::vector<std::string> skipped_properties;  // vertex properties we do not use
  splat::GaussianLabels labels;  // label_k / label_probability_k, where the file has them
};

// Reads a 3DGS map in the INRIA PLY layout (x y z [nx ny nz] f_dc_0..2 f_rest_* opacity
// scale_0..2 rot_0..3), ASCII or binary of either endianness. f_rest is channel-major and
// sets the SH degree; required properties must be float or double; other vertex properties are
// skipped and listed. Throws splat::Error naming the file and the offending element for a
// missing, truncated or malformed file and for NaN/Inf values.
PlyMap read_ply(const std::filesystem::path& path);

// Writes the map as binary little-endian float32 PLY in the INRIA layout (normals zero),
// atomically. Reading it back gives bit-identical arrays.
// With `labels` (not empty), each vertex also gets label_k (ushort class id) and
// label_probability_k (float) for k = 0..top-1, most probable first.
void write_ply(const std::filesystem::path& path, const splat::Gaussians& gaussians,
               const splat::GaussianLabels* labels = nullptr);

}  // namespace app
