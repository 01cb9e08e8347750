#version 450
// Compositing forward: one workgroup per 16x16 tile, one invocation per pixel. Splats of the
// tile's depth-sorted list are staged in shared memory kGroupSize at a time and blended front
// to back (gsplat's rules: skip alpha < kAlphaMin, stop before transmittance <= kTransmittanceMin).
// The workgroup leaves once every pixel has stopped. Reads bindings 0..7 (composite.glsl),
// writes 8..13. Deterministic.
#extension GL_GOOGLE_include_directive : require
#include "composite.glsl"

layout(local_size_x = 16, local_size_y = 16) in;
layout(std430, binding = 8) writeonly buffer OutRgb { float out_rgb[]; };      // [H, W, 3]
layout(std430, binding = 9) writeonly buffer OutAlpha { float out_alpha[]; };  // [H, W]
layout(std430, binding = 10) writeonly buffer OutDepth { float out_depth[]; }; // [H, W]
layout(std430, binding = 11) writeonly buffer OutDepthNorm { float out_depth_normalized[]; };
layout(std430, binding = 12) writeonly buffer OutLast { uint out_last[]; };    // [H, W]
layout(std430, binding = 13) writeonly buffer OutTrans { float out_transmittance[]; };

shared Splat batch[kGroupSize];
shared uint finished;

void main() {
  uint tid = gl_LocalInvocationIndex;
  uvec2 pixel = pixel_coord();
  bool inside = pixel_inside(pixel);
  vec2 centre = vec2(pixel) + 0.5;
  uint tile = tile_index();
  uint begin = tile_ranges[2 * tile], end = tile_ranges[2 * tile + 1];
  precise float t = 1.0;
  precise vec3 rgb = vec3(0);
  precise float z = 0;
  uint last = 0;
  bool done = !inside;  // pixels past the image edge never hold the tile open
  if (tid == 0u) finished = 0u;
  barrier();
  if (done) atomicAdd(finished, 1u);
  for (uint base = begin; base < end; base += kGroupSize) {
    barrier();  // the previous round's reads and finished counts are complete
    if (finished == kGroupSize) break;
    if (base + tid < end) batch[tid] = load_splat(sorted_ids[base + tid]);
    barrier();
    uint count = min(kGroupSize, end - base);
    for (uint k = 0u; k < count && !done; ++k) {
      Splat sp = batch[k];
      PixelEval e = eval_pixel(sp, centre);
      if (e.alpha < kAlphaMin) continue;
      precise float next_t = t * (1.0 - e.alpha);
      if (next_t <= kTransmittanceMin) {
        done = true;
        atomicAdd(finished, 1u);
        break;
      }
      precise float weight = e.alpha * t;
      rgb += weight * sp.color;
      z += weight * sp.depth;
      t = next_t;
      last = base + k + 1u;
    }
  }
  if (!inside) return;
  uint o = pixel.y * frame.width + pixel.x;
  vec3 bg = vec3(frame.background[0], frame.background[1], frame.background[2]);
  precise vec3 c = rgb + t * bg;
  out_rgb[3 * o] = c.r;
  out_rgb[3 * o + 1] = c.g;
  out_rgb[3 * o + 2] = c.b;
  precise float a = 1.0 - t;
  out_alpha[o] = a;
  out_depth[o] = z;
  out_depth_normalized[o] = a > 0 ? z / a : 0.0;
  out_last[o] = last;
  out_transmittance[o] = t;
}
