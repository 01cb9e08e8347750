#version 450
// Tiling, step 1: one invocation per depth-sorted position j gathers the tile count of the
// Gaussian there, so a scan gives each Gaussian's first intersection in depth order.
#extension GL_GOOGLE_include_directive : require
#include "shader_io.h"

layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer DepthOrder { uint depth_order[]; };  // [N]
layout(std430, binding = 1) readonly buffer TileCounts { uint tile_counts[]; };  // [N]
layout(std430, binding = 2) writeonly buffer Offsets { uint offsets[]; };        // [N]
layout(push_constant) uniform Push { uint count; } push;

void main() {
  uint j = gl_GlobalInvocationID.x;
  if (j < push.count) offsets[j] = tile_counts[depth_order[j]];
}
