#version 450
// Densification's median by radix selection, after each histogram pass (one invocation): the
// bin that holds the error of rank count / 2 (the host's std::nth_element index) among those
// left, added to the prefix; the rank left within it; the histogram zeroed for the next pass.
// After the last pass the prefix is the median's bits.
#extension GL_GOOGLE_include_directive : require
#include "shader_io.h"

layout(local_size_x = 1) in;
layout(std430, binding = 0) buffer Select { uint select_state[]; };  // kCoverageSelectWords
layout(std430, binding = 1) buffer Histogram { uint histogram[]; };  // [kCoverageBins]
layout(push_constant) uniform Push { uint shift; } push;

void main() {
  if (push.shift + kCoverageBits >= 32u) select_state[kCoverageRank] = select_state[kCoverageCount] / 2u;
  uint rank = select_state[kCoverageRank], below = 0u, bin = kCoverageBins - 1u;
  for (uint b = 0u; b < kCoverageBins; ++b) {
    uint n = histogram[b];
    if (below + n > rank) {
      bin = b;
      break;
    }
    below += n;
  }
  select_state[kCoveragePrefix] |= bin << push.shift;
  select_state[kCoverageRank] = rank - below;
  for (uint b = 0u; b < kCoverageBins; ++b) histogram[b] = 0u;
}
