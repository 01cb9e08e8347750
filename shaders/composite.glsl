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

// exp(x) for x <= 0 with the CPU reference's polynomial (Cephes, ~2 ulp), so both backends
// round alpha alike near the kAlphaMin and kTransmittanceMin cut-offs.
float exp_nonpositive(float x) {
  x = max(x, -87.0);
  float n = floor(x * 1.44269504088896341 + 0.5);
  float r = x - n * 0.693359375 + n * 2.12194440e-4;
  float p = 1.9875691500e-4;
  p = p * r + 1.3981999507e-3;
  p = p * r + 8.3334519073e-3;
  p = p * r + 4.1665795894e-2;
  p = p * r + 1.6666665459e-1;
  p = p * r + 5.0000001201e-1;
  p = p * r * r + r + 1.0;
  return p * intBitsToFloat((int(n) + 127) << 23);
}

struct PixelEval {
  float dx, dy, sigma, gauss;
  float alpha;      // min(kAlphaMax, opacity * gauss), 0 where sigma < 0
  float raw_alpha;  // before the cap
};

PixelEval eval_pixel(Splat s, vec2 pixel_centre) {
  PixelEval e;
  e.dx = s.mean.x - pixel_centre.x;
  e.dy = s.mean.y - pixel_centre.y;
  e.sigma = 0.5 * (s.conic.x * e.dx * e.dx + s.conic.z * e.dy * e.dy) + s.conic.y * e.dx * e.dy;
  e.gauss = exp_nonpositive(-max(e.sigma, 0.0));
  e.raw_alpha = e.sigma >= 0 ? s.opacity * e.gauss : 0.0;
  e.alpha = min(kAlphaMax, e.raw_alpha);
  return e;
}

// Tile of this workgroup (16x16 invocations, one per pixel) and this invocation's pixel.
uint tile_index() { return gl_WorkGroupID.y * frame.tiles_x + gl_WorkGroupID.x; }
uvec2 pixel_coord() { return gl_WorkGroupID.xy * kTileSize + gl_LocalInvocationID.xy; }
bool pixel_inside(uvec2 pixel) { return pixel.x < frame.width && pixel.y < frame.height; }

#endif  // GSLAM_COMPOSITE_GLSL
