// Class labels carried from 2D label images into the map: every Gaussian votes for the class of
// each pixel it is drawn into, weighted by its share of that pixel (its alpha-blending weight),
// over many views; its label distribution is the normalized votes. Votes are read from the
// rasterizer's own backward pass: with every Gaussian's colour a constant, the gradient of
// sum_p onehot_c(p) . colour(p) with respect to a Gaussian's colour is exactly its blending
// weight summed over the pixels of class c, three classes per pass (one per colour channel).
// Labels render the same way: each class's probability as a colour channel.
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "splat/camera.h"
#include "splat/gaussian_labels.h"
#include "splat/gaussians.h"
#include "splat/rasterizer.h"

namespace mapping {

class LabelFusion {
 public:
  explicit LabelFusion(std::size_t gaussians) : gaussians_(gaussians) {}
  // The votes of one view: `labels` [H, W] class ids at `camera`'s size (0 = unknown, no vote).
  // Throws splat::Error if the map or the labels do not fit.
  void add_view(splat::Rasterizer& rasterizer, const splat::Gaussians& map, const splat::Camera& camera,
                std::span<const uint16_t> labels);
  // Each Gaussian's `top` most probable classes (ids 0 and probability 0 past those it has votes for).
  splat::GaussianLabels result(int top = 3) const;
  std::size_t views() const { return views_; }

 private:
  std::size_t gaussians_;
  std::size_t views_ = 0;
  std::vector<uint16_t> classes_;            // class id of each vote column
  std::vector<std::vector<float>> votes_;    // per column, per Gaussian
  std::vector<float>& column(uint16_t id);
};

// Per pixel of `camera`'s view [H, W]: the class of highest rendered probability, 0 where the
// map covers less than `min_alpha` of the pixel or has no label there. Throws splat::Error if
// the labels do not fit the map.
std::vector<uint16_t> render_labels(splat::Rasterizer& rasterizer, const splat::Gaussians& map,
                                    const splat::GaussianLabels& labels, const splat::Camera& camera,
                                    double min_alpha = 0.5);

}  // namespace mapping
