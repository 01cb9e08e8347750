// Constants of the splatting model shared by every backend. Compiles as C++ and as GLSL, so the
// CPU reference and the compute shaders cannot drift apart. Values follow gsplat 1.5.3.
#ifndef GSLAM_SHADER_IO_H
#define GSLAM_SHADER_IO_H

#ifdef __cplusplus
#include <cstdint>
namespace splat::io {
using uint = std::uint32_t;
#define GSLAM_CONST inline constexpr
#else
#define GSLAM_CONST const
#endif

// Side of a square screen tile in pixels; one tile is one unit of compositing work.
GSLAM_CONST uint kTileSize = 16u;
// Per-splat alpha is capped so transmittance never reaches exactly zero (backward divides by 1-a).
GSLAM_CONST float kAlphaMax = 0.999f;
// Splats fainter than one 8-bit level at a pixel are skipped there.
GSLAM_CONST float kAlphaMin = 1.0f / 255.0f;
// A pixel stops compositing once its transmittance would fall to this value or below.
GSLAM_CONST float kTransmittanceMin = 1e-4f;
// Added to the diagonal of every 2D covariance (px^2): anti-aliasing low-pass filter.
GSLAM_CONST float kCov2dDilation = 0.3f;
// Largest screen extent in standard deviations; sqrt(2 ln 255) ~ 3.33 for an opaque splat.
GSLAM_CONST float kExtentSigmaMax = 3.33f;
// The point used in the projection Jacobian is clamped to the field of view widened by this
// fraction of tan(fov/2) on each side, so splats far off screen do not get huge footprints.
GSLAM_CONST float kFovClampMargin = 0.3f;

#ifdef __cplusplus
}  // namespace splat::io
#endif
#undef GSLAM_CONST
#endif  // GSLAM_SHADER_IO_H
