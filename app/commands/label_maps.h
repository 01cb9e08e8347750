// The map's classes from a sequence's label images (mapping/label_fusion.h), and how well the
// map renders them back (mIoU), for reconstruct and eval.
#pragma once
#include <cstdint>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "commands/run_outputs.h"
#include "datasets/dataset.h"
#include "splat/gaussian_labels.h"
#include "splat/gaussians.h"
#include "splat/rasterizer.h"

namespace app {

// Label images fused into the map at the end of reconstruct and live: views spread over the
// sequence (enough for every class to be seen from several sides; each costs a render and a
// backward pass per three classes).
inline constexpr std::size_t kLabelViews = 60;

// Votes of up to kLabelViews of the run's tracked frames that were not held out (matched to the
// dataset's entries by timestamp), spread over the run, each at 1/factor resolution with its
// pose in `poses` (one per record); frames without a label image are passed over. Shows
// progress. The map's classes go to `outputs` (map.ply, and "labels" in summary.json:
// {"classes": {"floor": Gaussians, ...}, "unlabelled": N, "ids": {"floor": 2, ...}}). Nothing
// if the dataset has no label images or the map is empty.
void fuse_run_labels(const Dataset& dataset, const std::vector<Eigen::Isometry3d>& poses, const splat::Gaussians& map,
                     splat::Rasterizer& rasterizer, int factor, RunOutputs& outputs);

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
