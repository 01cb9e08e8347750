#version 450
// The free-space test of each Gaussian's centre against a frame's depth (mapping's ghost
// evidence), one invocation per Gaussian from params.first on, in float and in the order the
// host's test computes it (mapping/src/mapper.cpp), each product and sum rounded on its own.
// Writes a 2-bit code per Gaussian into words zeroed beforehand.
#extension GL_GOOGLE_include_directive : require
#include "shader_io.h"

layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer Params { FreeSpaceParams params; };
layout(std430, binding = 1) readonly buffer Means { float means[]; };   // [N, 3]
layout(std430, binding = 2) readonly buffer Depth { float depth[]; };   // [H, W], 0 = none
layout(std430, binding = 3) readonly buffer Ignore { uint ignore[]; };  // [H, W] when has_ignore
layout(std430, binding = 4) buffer Codes { uint codes[]; };             // [ceil((N - first) / 16)]

void main() {
  uint j = gl_GlobalInvocationID.x;
  uint i = params.first + j;
  if (i >= params.count) return;
  precise float mx = means[3u * i], my = means[3u * i + 1u], mz = means[3u * i + 2u];
  precise float px = params.rotation[0] * mx + params.rotation[1] * my + params.rotation[2] * mz + params.translation[0];
  precise float py = params.rotation[3] * mx + params.rotation[4] * my + params.rotation[5] * mz + params.translation[1];
  precise float pz = params.rotation[6] * mx + params.rotation[7] * my + params.rotation[8] * mz + params.translation[2];
  if (!(pz > params.near_z)) return;
  precise float u = params.fx * px / pz + params.cx;
  precise float v = params.fy * py / pz + params.cy;
  if (!(u >= 1.0 && v >= 1.0 && u < float(params.width - 1u) && v < float(params.height - 1u))) return;
  int x = int(u), y = int(v);
  precise float margin = params.margin + params.margin_per_metre * pz;
  bool through = true, on = false;
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      uint k = uint(y + dy) * params.width + uint(x + dx);
      float z = depth[k];
      if (!(z > 0.0) || (params.has_ignore != 0u && ignore[k] != 0u)) return;
      through = through && z > pz + margin;
      on = on || abs(z - pz) <= margin;
    }
  }
  uint code = through ? kFreeSpaceThrough : (on ? kFreeSpaceOn : kFreeSpaceNone);
  if (code != kFreeSpaceNone) atomicOr(codes[j >> 4], code << ((j & 15u) * 2u));
}
