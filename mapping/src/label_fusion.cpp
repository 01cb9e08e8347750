#include "mapping/label_fusion.h"

#include <algorithm>
#include <numeric>
#include <string>

#include "splat/error.h"

namespace mapping {
namespace {

constexpr float kShC0 = 0.28209479177387814f;  // the SH DC basis: colour = kShC0 * dc + 0.5

// The map with every Gaussian's colour set by `colour(i, channel)` (view-independent: higher
// SH coefficients zero), its geometry unchanged.
template <typename Colour>
splat::Gaussians recoloured(const splat::Gaussians& map, Colour colour) {
  splat::Gaussians out;
  out.means = map.means;
  out.log_scales = map.log_scales;
  out.rotations = map.rotations;
  out.opacity_logits = map.opacity_logits;
  out.sh_degree = 0;
  out.sh.resize(map.size() * 3);
  for (std::size_t i = 0; i < map.size(); ++i) {
    for (int c = 0; c < 3; ++c) out.sh[i * 3 + c] = (colour(i, c) - 0.5f) / kShC0;
  }
  return out;
}

}  // namespace

std::vector<float>& LabelFusion::column(uint16_t id) {
  const auto it = std::find(classes_.begin(), classes_.end(), id);
  if (it != classes_.end()) return votes_[static_cast<std::size_t>(it - classes_.begin())];
  classes_.push_back(id);
  votes_.emplace_back(gaussians_, 0.f);
  return votes_.back();
}

void LabelFusion::add_view(splat::Rasterizer& rasterizer, const splat::Gaussians& map, const splat::Camera& camera,
                           std::span<const uint16_t> labels) {
  const std::size_t pixels = static_cast<std::size_t>(camera.width) * camera.height;
  if (map.size() != gaussians_ || labels.size() != pixels) {
    throw splat::Error("LabelFusion: a map of " + std::to_string(map.size()) + " Gaussians (expected " +
                       std::to_string(gaussians_) + ") and " + std::to_string(labels.size()) + " labels for " +
                       std::to_string(camera.width) + "x" + std::to_string(camera.height) + " pixels");
  }
  std::vector<uint16_t> present;
  for (const uint16_t id : labels) {
    if (id != 0 && std::find(present.begin(), present.end(), id) == present.end()) present.push_back(id);
  }
  if (present.empty() || map.empty()) return;
  ++views_;
  // Grey everywhere (0.5, inside the colour clamp): the gradient reaches every Gaussian.
  const splat::Gaussians grey = recoloured(map, [](std::size_t, int) { return 0.5f; });
  const splat::ForwardResult render = rasterizer.forward(grey, camera, splat::images_only());
  for (std::size_t first = 0; first < present.size(); first += 3) {
    splat::ImageGrads d;
    d.rgb.assign(pixels * 3, 0.f);
    const std::size_t count = std::min<std::size_t>(3, present.size() - first);
    for (std::size_t p = 0; p < pixels; ++p) {
      for (std::size_t c = 0; c < count; ++c) d.rgb[p * 3 + c] = labels[p] == present[first + c] ? 1.f : 0.f;
    }
    const splat::BackwardResult back = rasterizer.backward(render, d);
    for (std::size_t c = 0; c < count; ++c) {
      std::vector<float>& votes = column(present[first + c]);
      for (std::size_t i = 0; i < gaussians_; ++i) votes[i] += std::max(0.f, back.d_gaussians.sh[i * 3 + c] / kShC0);
    }
  }
}

splat::GaussianLabels LabelFusion::result(int top) const {
  if (top < 1) throw splat::Error("LabelFusion::result: top is " + std::to_string(top) + ", expected >= 1");
  splat::GaussianLabels out;
  out.top = top;
  out.ids.assign(gaussians_ * static_cast<std::size_t>(top), 0);
  out.probabilities.assign(out.ids.size(), 0.f);
  std::vector<std::size_t> order(classes_.size());
  for (std::size_t i = 0; i < gaussians_; ++i) {
    double total = 0;
    for (const std::vector<float>& v : votes_) total += v[i];
    if (!(total > 0)) continue;
    std::iota(order.begin(), order.end(), 0);
    const std::size_t kept = std::min<std::size_t>(static_cast<std::size_t>(top), order.size());
    std::partial_sort(order.begin(), order.begin() + static_cast<std::ptrdiff_t>(kept), order.end(),
                      [&](std::size_t a, std::size_t b) { return votes_[a][i] > votes_[b][i]; });
    for (std::size_t k = 0; k < kept && votes_[order[k]][i] > 0; ++k) {
      out.ids[i * static_cast<std::size_t>(top) + k] = classes_[order[k]];
      out.probabilities[i * static_cast<std::size_t>(top) + k] = static_cast<float>(votes_[order[k]][i] / total);
    }
  }
  return out;
}

std::vector<uint16_t> render_labels(splat::Rasterizer& rasterizer, const splat::Gaussians& map,
                                    const splat::GaussianLabels& labels, const splat::Camera& camera,
                                    double min_alpha) {
  const std::size_t pixels = static_cast<std::size_t>(camera.width) * camera.height;
  std::vector<uint16_t> out(pixels, 0);
  if (labels.empty() || map.empty()) return out;
  const auto top = static_cast<std::size_t>(labels.top);
  if (labels.ids.size() != map.size() * top || labels.probabilities.size() != labels.ids.size()) {
    throw splat::Error("render_labels: labels for " + std::to_string(labels.size()) + " Gaussians, the map has " +
                       std::to_string(map.size()));
  }
  std::vector<uint16_t> classes;
  for (const uint16_t id : labels.ids) {
    if (id != 0 && std::find(classes.begin(), classes.end(), id) == classes.end()) classes.push_back(id);
  }
  std::vector<float> best(pixels, 0.f);
  std::vector<float> alpha;
  for (std::size_t first = 0; first < classes.size(); first += 3) {
    const std::size_t count = std::min<std::size_t>(3, classes.size() - first);
    // Channel c: each Gaussian's probability of class first + c (+0.5 undone by the recolouring).
    const splat::Gaussians probability = recoloured(map, [&](std::size_t i, int c) {
      if (static_cast<std::size_t>(c) >= count) return 0.f;
      for (std::size_t k = 0; k < top; ++k) {
        if (labels.ids[i * top + k] == classes[first + static_cast<std::size_t>(c)]) return labels.probabilities[i * top + k];
      }
      return 0.f;
    });
    const splat::ForwardResult render = rasterizer.forward(probability, camera, splat::images_only());
    if (alpha.empty()) alpha = render.alpha;
    for (std::size_t p = 0; p < pixels; ++p) {
      for (std::size_t c = 0; c < count; ++c) {
        if (render.rgb[p * 3 + c] > best[p]) best[p] = render.rgb[p * 3 + c], out[p] = classes[first + c];
      }
    }
  }
  for (std::size_t p = 0; p < pixels; ++p) {
    if (alpha.empty() || alpha[p] < min_alpha) out[p] = 0;
  }
  return out;
}

}  // namespace mapping
