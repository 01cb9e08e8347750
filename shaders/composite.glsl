// What the compositing stages share: the per-splat screen parameters, their per-tile
// bindings (1..7, after the frame at 0), and the per-pixel evaluation (CPU: composite.cpp).
#ifndef GSLAM_COMPOSITE_GLSL
#define GSLAM_COMPOSITE_GLSL
#extension GL_GOOGLE_include_directive : require
#include "frame_params.glsl"

layout(std430, binding = 1) readonly buffer TileRanges { uint tile_ranges[]; };  // [T, 2]
layout(std430, binding = 2) readonly buffer SortedIds { uint sorted_ids[]; };    // [M]
layout(std430, binding = 3) readonly buffer Means2d { float means2d[]; };        // [N, 2]
layout(std430, binding = 4) readonly buffer Conics { float conics[]; };          // [N, 3]
layout(std430, binding = 5) readonly buffer Opacities { float opacities[]; };    // [N]
layout(std430, binding = 6) readonly buffer Colors { float colors[]; };          // [N, 3]
layout(std430, binding = 7) readonly buffer Depths { float depths[]; };          // [N]

struct Splat {
  vec2 mean;
  vec3 conic;  // a, b, c
  float opacity;
  vec3 color;
  float depth;
};

Splat load_splat(uint id) {
  Splat s;
  s.mean = vec2(means2d[2 * id], means2d[2 * id + 1]);
  s.conic = vec3(conics[3 * id], conics[3 * id + 1], conics[3 * id + 2]);
  s.opacity = opacities[id];
  s.color = vec3(colors[3 * id], colors[3 * id + 1], colors[3 * id + 2]);
  s.depth = depths[id];
  return s;
}

// The per-pixel maths, operation for operation as the CPU backend's (splat/src/cpu/
// composite_common.h, built without contraction): plain multiplies and adds marked `precise`,
// so no compiler fuses or reorders them and each is correctly rounded on every Vulkan device;
// alpha then agrees bit for bit with the CPU (tests/splat/composite_oracle_test.cpp). No fma():
// lavapipe computes it as a multiply and an add, NVIDIA as one operation.
//
// exp(x) for x <= 0: 2^n e^r, n = x / ln 2 rounded to nearest (ties to even), r = x - n ln 2
// with Cephes' two-part ln 2, e^r by a degree-5 minimax polynomial (about 2 ulp).
float exp_nonpositive(float x) {
  precise float y = max(x, -87.0);
  precise float n = roundEven(y * 1.44269504088896341);
  precise float r = y - n * 0.693359375 + n * 2.12194440e-4;
  precise float p = r * 8.290324360e-3 + 4.189795256e-2;
  p = p * r + 1.666763574e-1;
  p = p * r + 4.999915063e-1;
  p = p * r + 9.999997020e-1;
  p = p * r + 1.0;
  return p * intBitsToFloat((int(n) + 127) << 23);
}

struct PixelEval {
  float dx, dy, sigma, gauss;
  float alpha;      // min(kAlphaMax, opacity * gauss), 0 where sigma < 0
  float raw_alpha;  // before the cap
};

// sigma = dx (a/2 dx + b dy) + c/2 dy^2, (dx, dy) = mean - pixel centre.
PixelEval eval_pixel(Splat s, vec2 pixel_centre) {
  PixelEval e;
  precise float dx = s.mean.x - pixel_centre.x;
  precise float dy = s.mean.y - pixel_centre.y;
  precise float a_dx = (0.5 * s.conic.x) * dx;
  precise float b_dy = s.conic.y * dy;
  precise float c_dy2 = ((0.5 * s.conic.z) * dy) * dy;
  precise float sigma = dx * (a_dx + b_dy) + c_dy2;
  precise float gauss = exp_nonpositive(-sigma);
  precise float raw_alpha = sigma >= 0 ? s.opacity * gauss : 0.0;
  e.dx = dx;
  e.dy = dy;
  e.sigma = sigma;
  e.gauss = gauss;
  e.raw_alpha = raw_alpha;
  e.alpha = min(kAlphaMax, raw_alpha);
  return e;
}

// Tile of this workgroup (16x16 invocations, one per pixel) and this invocation's pixel.
uint tile_index() { return gl_WorkGroupID.y * frame.tiles_x + gl_WorkGroupID.x; }
uvec2 pixel_coord() { return gl_WorkGroupID.xy * kTileSize + gl_LocalInvocationID.xy; }
bool pixel_inside(uvec2 pixel) { return pixel.x < frame.width && pixel.y < frame.height; }

#endif  // GSLAM_COMPOSITE_GLSL
