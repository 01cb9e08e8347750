#version 450
// Pruning on the device: row i of `source` ([N, width] words) moves to row offsets[i] of
// `target` where bit i of keep_bits is set. offsets is the exclusive scan of the kept flags
// (compact_flags.comp, then the prefix sum), so kept rows stay in order.
#extension GL_GOOGLE_include_directive : require

layout(local_size_x = 256) in;
layout(std430, binding = 0) readonly buffer KeepBits { uint keep_bits[]; };  // [ceil(N / 32)]
layout(std430, binding = 1) readonly buffer Offsets { uint offsets[]; };     // [N]
layout(std430, binding = 2) readonly buffer Source { uint source[]; };       // [N, width]
layout(std430, binding = 3) writeonly buffer Target { uint target[]; };      // [kept, width]
layout(push_constant) uniform Push { uint count; uint width; } push;

void main() {
  uint i = gl_GlobalInvocationID.x;
  if (i >= push.count || (keep_bits[i >> 5] & (1u << (i & 31u))) == 0u) return;
  uint to = offsets[i] * push.width, from = i * push.width;
  for (uint k = 0u; k < push.width; ++k) target[to + k] = source[from + k];
}
