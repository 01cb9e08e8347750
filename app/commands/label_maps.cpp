#include "commands/label_maps.h"

#include "commands/progress.h"
#include "mapping/label_fusion.h"
#include "splat/error.h"

namespace app {

namespace {

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

}  // namespace

void fuse_run_labels(const Dataset& dataset, const std::vector<Eigen::Isometry3d>& poses, const splat::Gaussians& map,
                     splat::Rasterizer& rasterizer, int factor, RunOutputs& outputs) {
  if (!dataset.labels || map.empty()) return;
  // The run's usable frames as (dataset entry, pose), by timestamp.
  const std::vector<FrameRecord>& records = outputs.records();
  std::vector<double> entry_times, record_times;
  for (const DatasetEntry& e : dataset.entries) entry_times.push_back(e.timestamp);
  for (const FrameRecord& r : records) record_times.push_back(r.timestamp);
  std::vector<std::pair<std::size_t, Eigen::Isometry3d>> usable;
  for (const auto& [entry, record] : associate(entry_times, record_times, 1e-4)) {
    if (record < poses.size() && records[record].tracked && !records[record].held_out) usable.emplace_back(entry, poses[record]);
  }
  std::sort(usable.begin(), usable.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  const std::size_t views = std::min(usable.size(), kLabelViews);
  if (views == 0) return;
  Progress progress("labels", views, "views");
  mapping::LabelFusion fusion(map.size());
  for (std::size_t k = 0; k < views; ++k) {
    const auto& [entry, T_world_cam] = usable[k * usable.size() / views];
    const splat::RgbdFrame frame = dataset.load(entry);
    if (!frame.labels.empty()) {
      const splat::RgbdFrame small = splat::downsample(frame, factor);
      fusion.add_view(rasterizer, map, splat::posed(small.camera, T_world_cam.inverse()), small.labels);
    }
    progress.update(k + 1);
  }
  progress.finish();
  if (fusion.views() == 0) return;
  const splat::GaussianLabels labels = fusion.result();
  outputs.extra()["labels"] = labels_summary(*dataset.labels, labels);
  outputs.set_labels(labels);
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
