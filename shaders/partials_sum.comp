#version 450
// Adds per-workgroup partial sums on the device, so a mapping step downloads a few values
// instead of one row per workgroup: sums[k] = the sum over rows r of partials[r * width + k], in
// double and in a fixed order (each invocation strides over the rows, then a tree). One
// workgroup. The float variant (GSLAM_FLOAT_PARTIALS) reads float partials.
#extension GL_GOOGLE_include_directive : require
#include "shader_io.h"

layout(local_size_x = 256) in;
#ifdef GSLAM_FLOAT_PARTIALS
layout(std430, binding = 0) readonly buffer Partials { float partials[]; };   // [rows, width]
#else
layout(std430, binding = 0) readonly buffer Partials { double partials[]; };  // [rows, width]
#endif
layout(std430, binding = 1) writeonly buffer Sums { double sums[]; };  // [width]
layout(push_constant) uniform Push { uint rows; uint width; } push;

shared double reduction[kGroupSize];

void main() {
  uint tid = gl_LocalInvocationID.x;
  for (uint k = 0u; k < push.width; ++k) {
    double sum = 0.0lf;
    for (uint r = tid; r < push.rows; r += kGroupSize) sum += double(partials[r * push.width + k]);
    reduction[tid] = sum;
    barrier();
    for (uint s = kGroupSize / 2u; s > 0u; s >>= 1) {
      if (tid < s) reduction[tid] += reduction[tid + s];
      barrier();
    }
    if (tid == 0u) sums[k] = reduction[0];
    barrier();
  }
}
