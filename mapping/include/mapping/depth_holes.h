#pragma once
#include <span>
#include <vector>

namespace mapping {

// A depth map with its holes (values <= 0 or NaN) filled for seeding Gaussians there: each hole
// takes the largest of the nearest measurements left, right, above and below it. Depth cameras
// lose the far side of a depth edge (the shadow of the nearer surface) and what lies beyond their
// range, so the farther neighbour is the likelier surface; colour then corrects what depth
// could not say. Measured pixels keep their values; a map with no measurement stays all zero.
std::vector<float> fill_depth_holes(std::span<const float> depth, int width, int height);

}  // namespace mapping
