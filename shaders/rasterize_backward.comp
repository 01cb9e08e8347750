#version 450
// Compositing backward: one workgroup per 16x16 tile, one invocation per pixel, walking the
// tile's splats back to front from the last one any pixel used, a batch at a time in shared
// memory. Each splat's gradients are summed over the tile's pixels into its intersection's
// kGradSlots slots (every intersection belongs to one tile), in one of two ways:
// - GSLAM_FLOAT_ATOMICS (VK_EXT_shader_atomic_float): subgroupAdd, then float atomicAdds, one
//   per slot and subgroup; batches of kGroupSize splats. Subgroups add in varying order, so the
//   last bits vary from run to run.
// - portable: subgroupAdd, the partials kept in shared memory and summed in subgroup order after
//   each batch of kBackwardBatch splats; deterministic, more barriers.
// Reads bindings 0..12; writes 13 (zeroed by the host first, so intersections behind every
// pixel's last contributor keep zero).
#extension GL_GOOGLE_include_directive : require
#extension GL_KHR_shader_subgroup_basic : require
#extension GL_KHR_shader_subgroup_arithmetic : require
#extension GL_KHR_shader_subgroup_vote : require
#ifdef GSLAM_FLOAT_ATOMICS
#extension GL_EXT_shader_atomic_float : require
#endif
#include "composite.glsl"

layout(local_size_x = 16, local_size_y = 16) in;
layout(std430, binding = 8) readonly buffer LastContributor { uint last_contributor[]; };  // [H, W]
layout(std430, binding = 9) readonly buffer FinalTrans { float final_transmittance[]; };  // [H, W]
layout(std430, binding = 10) readonly buffer DRgb { float d_rgb[]; };      // [H, W, 3]
layout(std430, binding = 11) readonly buffer DAlpha { float d_alpha[]; };  // [H, W]
layout(std430, binding = 12) readonly buffer DDepth { float d_depth[]; };  // [H, W]
layout(std430, binding = 13) buffer IsectGrads { float isect_grads[]; };  // [M, kGradSlots]
// Which upstream gradients exist (an absent one is zero and its buffer is a placeholder).
layout(push_constant) uniform Push { uint has_rgb; uint has_alpha; uint has_depth; } push;

#ifdef GSLAM_FLOAT_ATOMICS
const uint kBatch = kGroupSize;
#else
const uint kBatch = kBackwardBatch;
shared float partials[kBatch][kGradSlots][kMaxSubgroups];
#endif
shared Splat batch[kBatch];
shared uint tile_last;

// A subgroup's sum of one gradient slot of splat s (batch entry k).
void store_sum(uint s, int k, uint slot, float sum) {
#ifdef GSLAM_FLOAT_ATOMICS
  atomicAdd(isect_grads[s * kGradSlots + slot], sum);
#else
  partials[k][slot][gl_SubgroupID] = sum;
#endif
}

void main() {
  // A lane for each slot. The workgroup (256 invocations, a multiple of every subgroup size)
  // fills its subgroups on lavapipe and NVIDIA, as this assumes (Vulkan promises it only with
  // REQUIRE_FULL_SUBGROUPS, 1.3). Counting the lanes present instead, a value the compiler can no
  // longer fold, made the backward 30% slower on an H100 (1.33-1.45 -> 1.75-1.93 ms).
  const bool lane_per_slot = gl_SubgroupSize >= kGradSlots;
  uint tid = gl_LocalInvocationIndex;
  uvec2 pixel = pixel_coord();
  bool inside = pixel_inside(pixel);
  vec2 centre = vec2(pixel) + 0.5;
  uint tile = tile_index();
  uint begin = tile_ranges[2 * tile];
  uint o = pixel.y * frame.width + pixel.x;
  // Per pixel: transmittance walking back to front, colour/depth behind the current splat,
  // upstream gradients and the background/alpha term T_final (dA - bg.dC).
  float t = 1.0;
  vec3 behind = vec3(0);
  float behind_z = 0;
  vec3 v_rgb = vec3(0);
  float v_z = 0, v_final = 0;
  uint last = 0u;
  if (inside) {
    t = final_transmittance[o];
    if (push.has_rgb != 0u) v_rgb = vec3(d_rgb[3 * o], d_rgb[3 * o + 1], d_rgb[3 * o + 2]);
    if (push.has_depth != 0u) v_z = d_depth[o];
    float v_a = push.has_alpha != 0u ? d_alpha[o] : 0.0;
    vec3 bg = vec3(frame.background[0], frame.background[1], frame.background[2]);
    v_final = t * (v_a - dot(bg, v_rgb));
    last = last_contributor[o];
  }
  if (tid == 0u) tile_last = 0u;
  barrier();
  atomicMax(tile_last, last);
  barrier();
  uint stop = max(tile_last, begin);
  for (uint hi = stop; hi > begin;) {
    uint lo = hi - min(kBatch, hi - begin);
    uint count = hi - lo;
    if (tid < count) batch[tid] = load_splat(sorted_ids[lo + tid]);
    barrier();
    for (int k = int(count) - 1; k >= 0; --k) {
      uint s = lo + uint(k);
      Splat sp = batch[k];
      PixelEval e = eval_pixel(sp, centre);
      bool used = s < last && e.alpha >= kAlphaMin;
      // A splat none of the subgroup's pixels use leaves their state as it is (its weight and
      // gradients are zero): skip its arithmetic and reductions. Most splats touch few of a
      // subgroup's pixels.
      if (!subgroupAny(used)) {
#ifndef GSLAM_FLOAT_ATOMICS
        if (subgroupElect()) {
          for (uint slot = 0u; slot < kGradSlots; ++slot) partials[k][slot][gl_SubgroupID] = 0;
        }
#endif
        continue;
      }
      float live = used ? 1.0 : 0.0;
      float inv = live / (1.0 - e.alpha);
      float t_front = live > 0 ? t * inv : t;  // transmittance in front of this splat
      float weight = live * e.alpha * t_front;
      // dL/dalpha: own contribution minus what it hides behind, plus the T_final terms.
      float v_alpha = dot(sp.color * t_front - behind * inv, v_rgb) +
                      (sp.depth * t_front - behind_z * inv) * v_z + v_final * inv;
      behind += weight * sp.color;
      behind_z += weight * sp.depth;
      t = t_front;
      // alpha = min(kAlphaMax, opacity * exp(-sigma)): no gradient where capped.
      float smooth_alpha = e.raw_alpha < kAlphaMax ? live : 0.0;
      float v_sigma = -smooth_alpha * sp.opacity * e.gauss * v_alpha;
      float g[kGradSlots];
      g[kSlotMeanX] = (sp.conic.x * e.dx + sp.conic.y * e.dy) * v_sigma;
      g[kSlotMeanY] = (sp.conic.z * e.dy + sp.conic.y * e.dx) * v_sigma;
      g[kSlotConicA] = 0.5 * e.dx * e.dx * v_sigma;
      g[kSlotConicB] = e.dx * e.dy * v_sigma;
      g[kSlotConicC] = 0.5 * e.dy * e.dy * v_sigma;
      g[kSlotOpacity] = smooth_alpha * e.gauss * v_alpha;
      g[kSlotRed] = weight * v_rgb.r;
      g[kSlotGreen] = weight * v_rgb.g;
      g[kSlotBlue] = weight * v_rgb.b;
      g[kSlotDepth] = weight * v_z;
      // Each slot's sum over the subgroup, stored (added into the intersection's slot, or kept
      // as this subgroup's partial) by lane `slot`: one store of kGradSlots lanes rather than
      // kGradSlots stores of one. Subgroups narrower than kGradSlots store one sum at a time.
      float mine = 0;
      for (uint slot = 0u; slot < kGradSlots; ++slot) {
        float sum = subgroupAdd(g[slot]);
        if (lane_per_slot) {
          if (gl_SubgroupInvocationID == slot) mine = sum;
        } else if (subgroupElect()) {
          store_sum(s, k, slot, sum);
        }
      }
      if (lane_per_slot && gl_SubgroupInvocationID < kGradSlots) {
        store_sum(s, k, gl_SubgroupInvocationID, mine);
      }
    }
#ifndef GSLAM_FLOAT_ATOMICS
    barrier();
    // Sum the subgroup partials of every (splat, slot) in subgroup order.
    for (uint item = tid; item < count * kGradSlots; item += kGroupSize) {
      uint k = item / kGradSlots, slot = item % kGradSlots;
      float sum = 0;
      for (uint sg = 0u; sg < gl_NumSubgroups; ++sg) sum += partials[k][slot][sg];
      isect_grads[(lo + k) * kGradSlots + slot] = sum;
    }
#endif
    barrier();
    hi = lo;
  }
}
