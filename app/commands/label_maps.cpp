#include "commands/label_maps.h"

#include "mapping/label_fusion.h"
#include "splat/error.h"

namespace app {

splat::GaussianLabels fuse_labels(const Dataset& dataset, const std::vector<Eigen::Isometry3d>& T_world_cam,
                                  const std::function<bool(std::size_t)>& use, const splat::Gaussians& map,
                                  splat::Rasterizer& rasterizer, int max_views, int factor,
                                  const std::function<void(std::size_t, std::size_t)>& visited) {
  if (!dataset.labels || map.empty() || max_views <= 0) return {};
  std::vector<std::size_t> candidates;
  for (std::size_t i = 0; i < dataset.entries.size() && i < T_world_cam.size(); ++i) {
    if (use(i)) candidates.push_back(i);
  }
  std::vector<std::size_t> chosen;
  const std::size_t wanted = std::min(candidates.size(), static_cast<std::size_t>(max_views));
  for (std::size_t k = 0; k < wanted; ++k) chosen.push_back(candidates[k * candidates.size() / wanted]);
  mapping::LabelFusion fusion(map.size());
  for (std::size_t k = 0; k < chosen.size(); ++k) {
    const std::size_t i = chosen[k];
    splat::RgbdFrame frame = dataset.load(i);
    if (!frame.labels.empty()) {
      const splat::RgbdFrame small = splat::downsample(frame, factor);
      fusion.add_view(rasterizer, map, splat::posed(small.camera, T_world_cam[i].inverse()), small.labels);
    }
    if (visited) visited(k + 1, chosen.size());
  }
  if (fusion.views() == 0) return {};
  return fusion.result();
}

nlohmann::json labels_summary(const LabelSet& set, const splat::GaussianLabels& labels) {
  std::map<std::string, std::size_t> counts;
  std::size_t unlabelled = 0;
  for (std::size_t i = 0; i < labels.size(); ++i) {
    if (labels.best(i) == 0) {
      ++unlabelled;
    } else {
      ++counts[set.name(labels.best(i))];
    }
  }
  std::map<std::string, uint16_t> ids;
  for (const LabelClass& c : set.classes) ids[c.name] = c.id;
  return {{"classes", counts}, {"unlabelled", unlabelled}, {"ids", ids}};
}

std::vector<uint8_t> label_colours(const std::vector<uint16_t>& labels) {
  // Twelve well-separated colours, cycled by id; unknown (0) is black.
  static const uint8_t palette[12][3] = {{230, 25, 75},  {60, 180, 75},   {255, 225, 25}, {0, 130, 200},
                                         {245, 130, 48}, {145, 30, 180},  {70, 240, 240}, {240, 50, 230},
                                         {210, 245, 60}, {250, 190, 212}, {0, 128, 128},  {170, 110, 40}};
  std::vector<uint8_t> rgb(labels.size() * 3, 0);
  for (std::size_t p = 0; p < labels.size(); ++p) {
    if (labels[p] == 0) continue;
    for (int c = 0; c < 3; ++c) rgb[p * 3 + static_cast<std::size_t>(c)] = palette[(labels[p] - 1) % 12][c];
  }
  return rgb;
}

void LabelScore::add(const std::vector<uint16_t>& rendered, const std::vector<uint16_t>& given) {
  if (rendered.size() != given.size()) {
    throw splat::Error("LabelScore: " + std::to_string(rendered.size()) + " rendered and " +
                       std::to_string(given.size()) + " given labels");
  }
  ++views_;
  for (std::size_t p = 0; p < given.size(); ++p) {
    const uint16_t truth = given[p], guess = rendered[p];
    if (truth == 0 || set_.is_dynamic(truth)) continue;
    ++pixels_;
    present_.insert(truth);
    if (truth == guess) {
      ++intersection_[truth];
      ++union_[truth];
    } else {
      ++union_[truth];
      if (guess != 0) ++union_[guess];
    }
  }
}

double LabelScore::iou(uint16_t id) const {
  const auto u = union_.find(id);
  const auto i = intersection_.find(id);
  return u == union_.end() || u->second == 0 ? 0 : static_cast<double>(i == intersection_.end() ? 0 : i->second) /
                                                        static_cast<double>(u->second);
}

double LabelScore::miou() const {
  double sum = 0;
  for (const uint16_t id : present_) sum += iou(id);
  return present_.empty() ? 0 : sum / static_cast<double>(present_.size());
}

nlohmann::json LabelScore::json() const {
  nlohmann::json per_class = nlohmann::json::object();
  for (const uint16_t id : present_) per_class[set_.name(id)] = iou(id);
  return {{"miou", miou()}, {"per_class", per_class}, {"views", views_}, {"pixels", pixels_}};
}

}  // namespace app
