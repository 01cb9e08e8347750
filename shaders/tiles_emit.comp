#version 450
// Tiling, step 2: one invocation per depth-sorted position j writes one (tile, instance) pair
// per tile its Gaussian touches, instances numbered in depth order, tiles row-major. A stable
// sort by tile then leaves every tile's list front to back, ties by Gaussian index, exactly as
// the CPU reference orders them. Also records each instance's Gaussian and each Gaussian's
// first instance, which the backward pass uses to gather its gradients without atomics.
#extension GL_GOOGLE_include_directive : require
#include "frame_params.glsl"
#include "tile_box.glsl"

layout(local_size_x = 256) in;
layout(std430, binding = 1) readonly buffer DepthOrder { uint depth_order[]; };  // [N]
layout(std430, binding = 2) readonly buffer Offsets { uint offsets[]; };         // [N] scanned
layout(std430, binding = 3) readonly buffer Means2d { float means2d[]; };        // [N, 2]
layout(std430, binding = 4) readonly buffer Radii { int radii[]; };              // [N, 2]
layout(std430, binding = 5) writeonly buffer TileKeys { uint tile_keys[]; };     // [M]
layout(std430, binding = 6) writeonly buffer Instances { uint instances[]; };    // [M] = index
layout(std430, binding = 7) writeonly buffer InstanceGaussian { uint instance_gaussian[]; };  // [M]
layout(std430, binding = 8) writeonly buffer FirstInstance { uint first_instance[]; };        // [N]

void main() {
  uint j = gl_GlobalInvocationID.x;
  if (j >= frame.count) return;
  uint g = depth_order[j];
  uint next = offsets[j];
  first_instance[g] = next;
  ivec2 radius = ivec2(radii[2 * g], radii[2 * g + 1]);
  if (radius.x <= 0 && radius.y <= 0) return;
  uvec2 lo, hi;
  tile_box(vec2(means2d[2 * g], means2d[2 * g + 1]), radius, lo, hi);
  for (uint ty = lo.y; ty < hi.y; ++ty) {
    for (uint tx = lo.x; tx < hi.x; ++tx) {
      tile_keys[next] = ty * frame.tiles_x + tx;
      instances[next] = next;
      instance_gaussian[next] = g;
      ++next;
    }
  }
}
