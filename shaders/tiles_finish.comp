#version 450
// Tiling, step 3: one invocation per sorted intersection s resolves its Gaussian
// (sorted_ids), records where each instance landed (for the backward gather), and marks the
// ends of each tile's range where the tile key changes. tile_ranges must be zeroed first.
#extension GL_GOOGLE_include_directive : require
#include "shader_io.h"

layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer TileKeys { uint tile_keys[]; };          // [M] sorted
layout(std430, binding = 1) readonly buffer Instances { uint instances[]; };         // [M] sorted
layout(std430, binding = 2) readonly buffer InstanceGaussian { uint instance_gaussian[]; };
layout(std430, binding = 3) writeonly buffer SortedIds { uint sorted_ids[]; };       // [M]
layout(std430, binding = 4) writeonly buffer SortedPosition { uint sorted_position[]; };  // [M]
layout(std430, binding = 5) buffer TileRanges { uint tile_ranges[]; };               // [T, 2]
layout(push_constant) uniform Push { uint count; } push;

void main() {
  uint s = gl_GlobalInvocationID.x;
  if (s >= push.count) return;
  uint instance = instances[s];
  sorted_ids[s] = instance_gaussian[instance];
  sorted_position[instance] = s;
  uint tile = tile_keys[s];
  if (s == 0u || tile_keys[s - 1u] != tile) tile_ranges[2 * tile] = s;
  if (s + 1u == push.count || tile_keys[s + 1u] != tile) tile_ranges[2 * tile + 1] = s + 1u;
}
