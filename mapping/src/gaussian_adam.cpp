#include "mapping/gaussian_adam.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "splat/error.h"

namespace mapping {

void remove_gaussians(splat::Gaussians& map, std::span<const uint8_t> keep) {
  if (keep.size() != map.size()) {
    throw splat::Error("remove_gaussians: keep has " + std::to_string(keep.size()) +
                       " entries, the map " + std::to_string(map.size()));
  }
  for (splat::ParamGroup group : splat::kAllParamGroups) {
    std::vector<float>& values = splat::param_group(map, group);
    const std::size_t width = static_cast<std::size_t>(splat::param_group_width(group, map.sh_degree));
    std::size_t out = 0;
    for (std::size_t i = 0; i < keep.size(); ++i) {
      if (!keep[i]) continue;
      for (std::size_t k = 0; k < width; ++k) values[out * width + k] = values[i * width + k];
      ++out;
    }
    values.resize(out * width);
  }
}

void GaussianAdam::append(std::size_t n, int sh_degree) {
  m_.sh_degree = v_.sh_degree = sh_degree;
  m_.resize(steps_.size() + n);
  v_.resize(steps_.size() + n);
  steps_.resize(steps_.size() + n, 0);
}

void GaussianAdam::remove(std::span<const uint8_t> keep) {
  if (keep.size() != steps_.size()) {
    throw splat::Error("GaussianAdam::remove: keep has " + std::to_string(keep.size()) +
                       " entries, the optimizer " + std::to_string(steps_.size()));
  }
  remove_gaussians(m_, keep);
  remove_gaussians(v_, keep);
  std::size_t out = 0;
  for (std::size_t i = 0; i < keep.size(); ++i)
    if (keep[i]) steps_[out++] = steps_[i];
  steps_.resize(out);
}

void GaussianAdam::restore(State state) {
  splat::validate_sizes<float>(state.m, "GaussianAdam first moment");
  splat::validate_sizes<float>(state.v, "GaussianAdam second moment");
  if (state.m.size() != state.steps.size() || state.v.size() != state.steps.size() ||
      state.m.sh_degree != state.v.sh_degree) {
    throw splat::Error("GaussianAdam::restore: moments for " + std::to_string(state.m.size()) + " and " +
                       std::to_string(state.v.size()) + " Gaussians, step counts for " +
                       std::to_string(state.steps.size()));
  }
  m_ = std::move(state.m);
  v_ = std::move(state.v);
  steps_ = std::move(state.steps);
}

void GaussianAdam::ensure_layout(const splat::Gaussians& map) {
  if (steps_.empty() && m_.empty()) {
    append(map.size(), map.sh_degree);  // first step: state for the whole map
  }
  if (map.size() != steps_.size() || map.sh_degree != m_.sh_degree) {
    throw splat::Error("GaussianAdam::step: the map has " + std::to_string(map.size()) +
                       " Gaussians (SH degree " + std::to_string(map.sh_degree) +
                       "), the optimizer state " + std::to_string(steps_.size()) +
                       "; call append/remove with every change to the map");
  }
}

void GaussianAdam::step(splat::Gaussians& map, const splat::GaussianGrads& grads, double lr_scale,
                        splat::ThreadPool* pool) {
  ensure_layout(map);
  splat::validate_sizes(splat::GaussiansView(grads), "GaussianAdam::step gradients");
  if (grads.size() != map.size() || grads.sh_degree != map.sh_degree) {
    throw splat::Error("GaussianAdam::step: gradients for " + std::to_string(grads.size()) +
                       " Gaussians, map has " + std::to_string(map.size()));
  }
  const std::size_t n = map.size();
  // Bias corrections per Gaussian. Step counts repeat across the map (Gaussians added
  // together share them), so the powers of each count are computed once and kept.
  uint32_t most = 0;
  for (uint32_t& t : steps_) most = std::max(most, ++t);
  while (beta1_powers_.size() <= most) {
    beta1_powers_.push_back(std::pow(config_.hyper.beta1, double(beta1_powers_.size())));
    beta2_powers_.push_back(std::pow(config_.hyper.beta2, double(beta2_powers_.size())));
  }
  constexpr std::size_t kChunk = 4096;
  splat::parallel_for(pool, (n + kChunk - 1) / kChunk, [&](std::size_t chunk) {
    const std::size_t begin = chunk * kChunk, count = std::min(n, begin + kChunk) - begin;
    double bias1[kChunk], bias2[kChunk];
    for (std::size_t i = 0; i < count; ++i) {
      bias1[i] = 1 - beta1_powers_[steps_[begin + i]];
      bias2[i] = 1 - beta2_powers_[steps_[begin + i]];
    }
    for (splat::ParamGroup group : splat::kAllParamGroups) {
      const std::size_t width = static_cast<std::size_t>(splat::param_group_width(group, map.sh_degree));
      float* p = splat::param_group(map, group).data() + begin * width;
      const float* g = splat::param_group(grads, group).data() + begin * width;
      float* m = splat::param_group(m_, group).data() + begin * width;
      float* v = splat::param_group(v_, group).data() + begin * width;
      // Column by column, so the Gaussians' loop vectorizes (strided by the group's width).
      for (std::size_t c = 0; c < width; ++c) {
        double lr = 0;
        switch (group) {
          case splat::ParamGroup::kMeans: lr = config_.means; break;
          case splat::ParamGroup::kLogScales: lr = config_.log_scales; break;
          case splat::ParamGroup::kRotations: lr = config_.rotations; break;
          case splat::ParamGroup::kOpacityLogits: lr = config_.opacity_logits; break;
          case splat::ParamGroup::kSh: lr = c < 3 ? config_.sh_dc : config_.sh_rest; break;
        }
        lr *= lr_scale;
#pragma omp simd
        for (std::size_t i = 0; i < count; ++i) {
          const std::size_t j = i * width + c;
          splat::adam_update(p[j], g[j], m[j], v[j], lr, bias1[i], bias2[i], config_.hyper);
        }
      }
    }
  });
}

}  // namespace mapping
