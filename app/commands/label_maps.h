// The map's classes from a sequence's label images (mapping/label_fusion.h), and how well the
// map renders them back (mIoU), for reconstruct and eval.
#pragma once
#include <cstdint>
#include <functional>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "datasets/dataset.h"
#include "splat/gaussian_labels.h"
#include "splat/gaussians.h"
#include "splat/rasterizer.h"

namespace app {

// Label images fused into the map by reconstruct: views spread over the sequence (enough for
// every class to be seen from several sides; each costs a render and a backward pass per three
// classes).
inline constexpr std::size_t kLabelViews = 60;

// Votes of up to `max_views` frames, spread evenly over those `use(i)` accepts, each at 1/factor
// resolution with its pose T_world_cam[i]; frames without a label image are passed over.
// `visited(done, total)` after each. Empty labels if the dataset has none.
splat::GaussianLabels fuse_labels(const Dataset& dataset, const std::vector<Eigen::Isometry3d>& T_world_cam,
                                  const std::function<bool(std::size_t)>& use, const splat::Gaussians& map,
                                  splat::Rasterizer& rasterizer, int max_views, int factor,
                                  const std::function<void(std::size_t, std::size_t)>& visited = {});

// What the map holds, for summary.json: {"classes": {"floor": Gaussians, ...}, "unlabelled": N}.
nlohmann::json labels_summary(const LabelSet& set, const splat::GaussianLabels& labels);

// Label images drawn in a fixed palette (unknown: black), [H, W, 3] 8-bit.
std::vector<uint8_t> label_colours(const std::vector<uint16_t>& labels);

// Intersection over union per class between rendered and given labels, summed over views. Pixels
// given 0 (unknown) or a dynamic class (the map holds the static scene) are not scored.
class LabelScore {
 public:
  explicit LabelScore(const LabelSet& set) : set_(set) {}
  void add(const std::vector<uint16_t>& rendered, const std::vector<uint16_t>& given);
  std::size_t views() const { return views_; }
  // {"miou": ..., "per_class": {"floor": 0.97, ...}, "views": N, "pixels": P}; mIoU over the
  // classes present in the given labels.
  nlohmann::json json() const;
  double miou() const;
  double iou(uint16_t id) const;

 private:
  const LabelSet& set_;
  std::map<uint16_t, std::size_t> intersection_, union_;
  std::set<uint16_t> present_;  // classes the given labels hold (scored)
  std::size_t views_ = 0, pixels_ = 0;
};

}  // namespace app
