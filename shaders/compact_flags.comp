#version 450
// Pruning on the device, step 1: the keep bit of each Gaussian as a uint, for the prefix sum
// that gives each kept Gaussian its new index (compact.comp).
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer KeepBits { uint keep_bits[]; };  // [ceil(N / 32)]
layout(std430, binding = 1) writeonly buffer Flags { uint flags[]; };        // [N]
layout(push_constant) uniform Push { uint count; } push;

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i < push.count) flags[i] = (keep_bits[i >> 5] >> (i & 31u)) & 1u;
}
