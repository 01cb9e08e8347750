#version 450
// Mapping loss, one pass of the D-SSIM window's separable blur (losses.cpp blur(): zero padding,
// taps summed in order from -kSsimRadius): one invocation per pixel of one plane; workgroups
// along x cover the pixels, along y the planes. The window is symmetric, so the same passes
// are the adjoint blur of the SSIM gradient. Reads 1, writes 2. Deterministic.
#extension GL_GOOGLE_include_directive : require
#include "loss_pixel.glsl"

layout(local_size_x = 256) in;
layout(std430, binding = 1) readonly buffer Source { float source[]; };  // [planes, H, W]
layout(std430, binding = 2) writeonly buffer Blurred { float blurred[]; };  // [planes, H, W]
layout(push_constant) uniform Push {
  uint vertical;  // 0: along rows (x), 1: along columns (y)
};

void main() {
  uint p = gl_GlobalInvocationID.x;
  uint pixels = pixel_count();
  if (p >= pixels) return;
  uint base = gl_WorkGroupID.y * pixels;
  int x = int(p % params.width), y = int(p / params.width);
  int along = vertical != 0u ? y : x;
  int extent = int(vertical != 0u ? params.height : params.width);
  int stride = vertical != 0u ? int(params.width) : 1;
  float sum = 0.0;
  for (int k = -int(kSsimRadius); k <= int(kSsimRadius); ++k) {
    int at = along + k;
    if (at < 0 || at >= extent) continue;  // zero padding
    sum += params.taps[k + int(kSsimRadius)] * source[base + uint(int(p) + k * stride)];
  }
  blurred[base + p] = sum;
}
