#pragma once
#include <cstdint>
#include <span>
#include <vector>

namespace mapping {

// Pixels near a depth edge, where a depth camera's measurements are least trustworthy (mixed
// and flying pixels, and a registration to colour that is off by a pixel or two): 1 within
// `radius` pixels (a square) of a pair of measured 4-neighbours whose depths differ by more than
// `jump` x the nearer one, or of a measured pixel next to one without a measurement; 0 elsewhere.
std::vector<uint8_t> depth_edges(std::span<const float> depth, int width, int height, double jump, int radius);

}  // namespace mapping
