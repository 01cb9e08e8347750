#pragma once
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "splat/gaussian_labels.h"
#include "splat/gaussians.h"

namespace app {

// One glTF POINTS primitive carrying KHR_gaussian_splatting attributes, decoded to floats
// (normalized integer accessors mapped to [-1, 1] / [0, 1] as glTF defines) and moved to the
// world frame by its node's transform.
struct GltfSplatPrimitive {
  std::string name;                 // node name, else mesh name
  std::vector<float> positions;     // [N, 3]
  std::vector<float> rotations_xyzw;  // [N, 4] as stored: x, y, z, w
  std::vector<float> log_scales;    // [N, 3] natural log of SCALE (see read_gltf_splats)
  std::vector<float> opacities;     // [N] in [0, 1]
  std::vector<float> sh;            // [N, K, 3]
  int sh_degree = 0;
  std::string kernel;       // as stored; unknown kernels fall back to "ellipse"
  std::string color_space;  // as stored; unknown ones are treated as srgb_rec709_display
  bool sh_from_color0 = false;  // no SH_DEGREE_0 attribute: DC derived from COLOR_0
  double node_scale = 1;        // the node transform's uniform scale, folded into log_scales
  splat::GaussianLabels labels;  // _LABEL_k and _LABEL_PROBABILITY_k (write_gltf), if present
};

struct GltfSplatScene {
  std::vector<GltfSplatPrimitive> primitives;
  bool older_draft = false;  // SCALE held log-scales and COLOR_0 display values (read_gltf_splats)
  std::vector<std::string> notices;  // fallbacks taken (unknown kernel, colour space, ...)
};

// Reads every KHR_gaussian_splatting primitive of a .gltf or .glb file, in the scene's frame (node
// transforms applied), except the transform of a node carrying write_gltf's axis-rotation mark:
// gslam's own files read back in the world frame they were written from. SCALE is linear and
// never negative in the extension's text since April 2026; drafts before it stored log-scales,
// and their writers COLOR_0 as display (sRGB-encoded) values. The rule: a file with any negative
// SCALE value was written to an older draft, and all its SCALEs are read as log-scales and its
// COLOR_0 as display values; otherwise SCALE is linear (0 read as 1e-12 m) and COLOR_0 linear, as
// glTF defines vertex colours. Throws splat::Error
// naming the file and the element for unreadable files, missing or malformed attributes,
// partially defined SH degrees, non-similarity node transforms and NaN/Inf values.
GltfSplatScene read_gltf_splats(const std::filesystem::path& path);

// Merges the primitives into one map (highest SH degree; missing coefficients are zero).
// The labels of the primitives, where every one has as many classes per Gaussian.
splat::GaussianLabels to_labels(const GltfSplatScene& scene);
// Opacities are clamped to [1e-6, 1 - 1e-6] before the logit so 0 and 1 stay finite.
splat::Gaussians to_gaussians(const GltfSplatScene& scene);

// The rotation from a map's world frame to glTF's axes (+Y up, right-handed, metres) that takes
// `world_up` (world frame, any length) to +Y and the world's +z (the first camera's view
// direction in a gslam map), levelled, to -Z: a glTF viewer's default camera, looking down -Z,
// then looks where the first camera did. For world_up = -y (a level OpenCV camera) it is the
// usual OpenCV-to-glTF turn, 180 degrees about x. Throws splat::Error for a zero or non-finite up.
Eigen::Quaterniond gltf_rotation_for_up(const Eigen::Vector3d& world_up);

// Writes the map as a .glb (or .gltf with embedded buffers, by extension) with one POINTS
// primitive: POSITION, KHR_gaussian_splatting ROTATION (unit, xyzw), SCALE (linear, metres),
// OPACITY, SH_DEGREE_l_COEF_n for every degree of the map, and COLOR_0 (diffuse colour in linear
// light, and opacity) for viewers without the extension. The attributes hold the map as it is
// (its world frame); `gltf_from_world`, unless the identity, becomes the rotation of the node
// that carries them (the extension derives each splat's covariance from its attributes and the
// node's transform, so the splats are in the node's local frame; SH coefficients, in that frame
// too, are left as they are), marked in the node's extras
// (`"gslam": {"node_rotation": "world_to_gltf"}`) so that read_gltf_splats gives the map back in
// its world frame.
// With `labels` (a semantic map), the Gaussians' classes go into the application-specific
// attributes _LABEL_k (class id) and _LABEL_PROBABILITY_k, k = 0..top-1, as floats (glTF keeps
// vertex attributes 4-byte aligned; ids up to 65535 are exact).
void write_gltf(const std::filesystem::path& path, const splat::Gaussians& gaussians,
                const Eigen::Quaterniond& gltf_from_world = Eigen::Quaterniond::Identity(),
                const splat::GaussianLabels* labels = nullptr);

}  // namespace app
