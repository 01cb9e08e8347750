// What each Gaussian of a map is: its most probable classes (ids from the label images a
// sequence came with) and their probabilities, fused from many views (mapping/label_fusion.h).
#pragma once
#include <cstdint>
#include <vector>

namespace splat {

struct GaussianLabels {
  int top = 0;  // classes kept per Gaussian, most probable first; 0: the map has no labels
  std::vector<uint16_t> ids;         // [N, top] class ids; 0 = unknown (no vote)
  std::vector<float> probabilities;  // [N, top] in [0, 1]
  bool empty() const { return top == 0; }
  std::size_t size() const { return top > 0 ? ids.size() / static_cast<std::size_t>(top) : 0; }
  // Gaussian i's most probable class (0 if unknown).
  uint16_t best(std::size_t i) const { return top > 0 ? ids[i * static_cast<std::size_t>(top)] : 0; }
};

}  // namespace splat
