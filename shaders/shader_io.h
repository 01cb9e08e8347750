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

// Gradient slots per (tile, splat) intersection in the backward pass, in this order.
GSLAM_CONST uint kSlotMeanX = 0u;
GSLAM_CONST uint kSlotMeanY = 1u;
GSLAM_CONST uint kSlotConicA = 2u;
GSLAM_CONST uint kSlotConicB = 3u;
GSLAM_CONST uint kSlotConicC = 4u;
GSLAM_CONST uint kSlotOpacity = 5u;
GSLAM_CONST uint kSlotRed = 6u;
GSLAM_CONST uint kSlotGreen = 7u;
GSLAM_CONST uint kSlotBlue = 8u;
GSLAM_CONST uint kSlotDepth = 9u;
GSLAM_CONST uint kGradSlots = 10u;
// Forward-mode pose derivatives per Gaussian: mean x, y, conic a, b, c, depth, colour r, g, b,
// each for the 6 pose directions: [N, kScreenValues, 6].
GSLAM_CONST uint kScreenValues = 9u;
// Per-pixel pose Jacobian outputs: r, g, b, depth, alpha.
GSLAM_CONST uint kPoseJacobianOutputs = 5u;
// Pose-gradient partial sums per workgroup: dL/dW (3x3, row-major) then dL/dt (3).
GSLAM_CONST uint kPosePartials = 12u;

// Vulkan compute: invocations per workgroup of the 1D stages, and keys per radix-sort block.
GSLAM_CONST uint kGroupSize = 256u;
// Radix sort: bits per pass and bins; one key per invocation, kGroupSize keys per block.
GSLAM_CONST uint kRadixBits = 4u;
GSLAM_CONST uint kRadixBins = 16u;
// Prefix sum: elements per workgroup (4 per invocation).
GSLAM_CONST uint kScanBlock = 1024u;
// Splats staged in shared memory per round of the backward and pose-Jacobian compositing.
GSLAM_CONST uint kBackwardBatch = 16u;
// Backward reduction: most subgroups per 256-invocation workgroup (subgroup size >= 8).
GSLAM_CONST uint kMaxSubgroups = 32u;

// Cull reasons written by the projection stage (RenderStats counts them).
GSLAM_CONST uint kCullNone = 0u;
GSLAM_CONST uint kCullDepth = 1u;
GSLAM_CONST uint kCullDegenerate = 2u;
GSLAM_CONST uint kCullFaint = 3u;
GSLAM_CONST uint kCullOffscreen = 4u;

// Per-frame parameters every Vulkan stage reads (one storage buffer, std430: scalars and
// scalar arrays only, so the C++ and GLSL layouts agree byte for byte).
struct FrameParams {
  float fx, fy, cx, cy;
  float near_z, far_z;
  float rotation[9];     // W of p_cam = W p_world + t, row-major
  float translation[3];  // t
  float cam_position[3]; // camera centre in the world, -W^T t
  float background[3];
  // Bounds on x/z and y/z for the projection Jacobian (see kFovClampMargin).
  float lim_x_neg, lim_x_pos, lim_y_neg, lim_y_pos;
  uint width, height, tiles_x, tiles_y;
  uint count;            // Gaussians
  int sh_degree;         // degree evaluated
  uint sh_stride;        // SH coefficients per Gaussian in the map, (map degree + 1)^2
  uint sh_direction_gradient;  // 1: backpropagate through the SH view direction
};

// The mapping loss (splat::MappingLoss, src/vulkan/mapping_loss.cpp). Per-workgroup partial sums
// of its shaders, kLossPartials doubles per workgroup of kGroupSize pixels, in these slots:
GSLAM_CONST uint kLossColorL1 = 0u;     // sum of |recorded - target| over the colour channels
GSLAM_CONST uint kLossDepthL1 = 1u;     // sum of |depth residual| over measured pixels
GSLAM_CONST uint kLossDssim = 2u;       // sum of 1 - SSIM over the colour channels
GSLAM_CONST uint kLossVignetteK1 = 3u;  // dL/dk1
GSLAM_CONST uint kLossVignetteK2 = 4u;  // dL/dk2
GSLAM_CONST uint kLossPartials = 5u;
// D-SSIM statistics per colour channel: x, y, x^2, y^2, xy (x recorded, y target); the SSIM
// gradient has three per channel: dS/d(mu_x), dS/d(E[x^2]), dS/d(E[xy]) (losses.cpp's da, db, dc).
GSLAM_CONST uint kSsimStats = 5u;
GSLAM_CONST uint kSsimGrads = 3u;
// The D-SSIM window: 11 taps, a Gaussian of sigma 1.5.
GSLAM_CONST uint kSsimRadius = 5u;
GSLAM_CONST uint kSsimTaps = 11u;

// One mapping-loss evaluation (storage buffer, std430, scalars only; doubles first so C++ and
// GLSL agree on every offset). The doubles keep the CPU's precision where it computes in double.
struct LossParams {
  double fx, fy, cx, cy;  // pixels
  double k1, k2;          // vignetting gain 1 + k1 r^2 + k2 r^4
  double color_scale;     // color_weight / (3 W H)
  double depth_scale;     // depth_weight / measured pixels; 0 when none is measured
  double alpha_threshold; // depth is normalized by alpha above this
  float ssim_scale;       // ssim_weight / (3 W H), in the D-SSIM's float precision
  float taps[kSsimTaps];  // normalized window, computed on the host as losses.cpp does
  uint width, height;
  uint has_ignore;        // 1: the ignore mask is bound
  uint ssim;              // 1: the D-SSIM term is on
};

// The resident map's stages (src/vulkan/resident_map.cpp).
// Floats per Gaussian of the geometry gradients and moments: means 3, log-scales 3, rotation 4,
// opacity logit 1 (project_backward.comp's d_params layout).
GSLAM_CONST uint kGeometryFloats = 11u;

// One Adam step (storage buffer, std430, scalars only; the doubles first). Learning rates
// already include the step's scale; bias corrections are computed per Gaussian from its own
// step count, in double as the CPU does (beta2^t in float is off by 1e-4 at small t).
struct AdamParams {
  double beta1, beta2;
  float lr_means, lr_log_scales, lr_rotations, lr_opacity, lr_sh_dc, lr_sh_rest;
  float eps;
  uint count;      // Gaussians
  uint sh_floats;  // SH floats per Gaussian, K * 3
  uint isotropic;  // 1: the three log-scales move by their mean gradient, rotations not at all
};

// The free-space test of Gaussian centres against a stored frame's depth (free_space_test.comp;
// ResidentMap::free_space_test). Codes, 2 bits per Gaussian, 16 per word:
// Densification's coverage test (coverage_*.comp): the median depth error by radix selection,
// kCoverageBits bits a pass from the top; its state words, and the key of a pixel with no error.
GSLAM_CONST uint kCoverageBits = 8u;
GSLAM_CONST uint kCoverageBins = 256u;
GSLAM_CONST uint kCoverageNoError = 0xffffffffu;
GSLAM_CONST uint kCoverageCount = 0u;   // errors counted
GSLAM_CONST uint kCoveragePrefix = 1u;  // the median's bits chosen so far
GSLAM_CONST uint kCoverageRank = 2u;    // its rank among the errors that match the prefix
GSLAM_CONST uint kCoverageSelectWords = 4u;

GSLAM_CONST uint kFreeSpaceNone = 0u;     // no verdict: off the image, too near, a neighbour unmeasured
GSLAM_CONST uint kFreeSpaceThrough = 1u;  // every depth around it is farther by more than the margin
GSLAM_CONST uint kFreeSpaceOn = 2u;       // a depth around it is within the margin
struct FreeSpaceParams {
  float fx, fy, cx, cy;
  float rotation[9];     // W of p_cam = W p_world + t, row-major
  float translation[3];  // t
  float near_z;          // centres nearer than this get no verdict
  float margin, margin_per_metre;  // the margin at depth z: margin + margin_per_metre * z
  uint width, height;
  uint first, count;     // Gaussians [first, count) are tested
  uint has_ignore;       // 1: the ignore mask is bound; ignored pixels count as unmeasured
};

#ifdef __cplusplus
}  // namespace splat::io
#endif
#undef GSLAM_CONST
#endif  // GSLAM_SHADER_IO_H
