#ifndef GSLAM_TILE_BOX_GLSL
#define GSLAM_TILE_BOX_GLSL
// Tiles [lo, hi) touched by a splat's per-axis extent box, clamped to the grid (gsplat's
// isect_tiles; tile_box in the CPU reference).
void tile_box(vec2 mean2d, ivec2 radius, out uvec2 lo, out uvec2 hi) {
  float tile = float(kTileSize);
  vec2 m = mean2d / tile, e = vec2(radius) / tile, grid = vec2(frame.tiles_x, frame.tiles_y);
  lo = uvec2(clamp(floor(m - e), vec2(0), grid));
  hi = uvec2(clamp(ceil(m + e), vec2(0), grid));
}

#endif  // GSLAM_TILE_BOX_GLSL
