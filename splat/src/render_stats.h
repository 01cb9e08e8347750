// RenderStats from the projection stage's per-Gaussian cull reasons (io::kCull*), for both
// backends.
#pragma once
#include <cstdint>
#include <span>

#include "shader_io.h"
#include "splat/rasterizer.h"

namespace splat {

inline RenderStats tally_cull_reasons(std::span<const uint32_t> reasons) {
  RenderStats stats;
  for (uint32_t r : reasons) {
    switch (r) {
      case io::kCullNone:
        ++stats.visible;
        break;
      case io::kCullDepth:
        ++stats.culled_depth;
        break;
      case io::kCullDegenerate:
        ++stats.culled_degenerate;
        break;
      case io::kCullFaint:
        ++stats.culled_faint;
        break;
      default:
        ++stats.culled_offscreen;
        break;
    }
  }
  return stats;
}

}  // namespace splat
