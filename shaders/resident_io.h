// Parameters of the resident map's stages (splat/src/vulkan/resident_map.cpp): Adam and
// compaction. Compiles as C++ and as GLSL, like shader_io.h.
#ifndef GSLAM_RESIDENT_IO_H
#define GSLAM_RESIDENT_IO_H

#ifdef __cplusplus
#include <cstdint>
namespace splat::io {
using uint = std::uint32_t;
#define GSLAM_CONST inline constexpr
#else
#define GSLAM_CONST const
#endif

// Floats per Gaussian of the geometry gradients and moments: means 3, log-scales 3, rotation 4,
// opacity logit 1 (project_backward.comp's d_params layout).
GSLAM_CONST uint kGeometryFloats = 11u;

// One Adam step (storage buffer, std430, scalars only). Learning rates already include the
// step's scale; bias corrections are computed per Gaussian from its own step count.
struct AdamParams {
  float lr_means, lr_log_scales, lr_rotations, lr_opacity, lr_sh_dc, lr_sh_rest;
  float beta1, beta2, eps;
  uint count;      // Gaussians
  uint sh_floats;  // SH floats per Gaussian, K * 3
  uint isotropic;  // 1: the three log-scales move by their mean gradient, rotations not at all
};

#ifdef __cplusplus
}  // namespace splat::io
#endif
#undef GSLAM_CONST
#endif  // GSLAM_RESIDENT_IO_H
