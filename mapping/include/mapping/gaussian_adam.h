#pragma once
#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "splat/adam.h"
#include "splat/gaussians.h"
#include "splat/thread_pool.h"

namespace mapping {

// Learning rate per parameter group (means in metres: scaled by the scene by the caller).
struct AdamConfig {
  double means = 1e-4;
  double log_scales = 5e-3;
  double rotations = 1e-3;
  double opacity_logits = 5e-2;
  double sh_dc = 2.5e-3;    // SH coefficient 0
  double sh_rest = 1.25e-4; // higher SH degrees (3DGS: dc / 20)
  splat::AdamHyper hyper;
};

// Adam over a map, one state per Gaussian that follows it: append() and remove() keep the
// moments and step counts aligned with the Gaussians they belong to. Each Gaussian has its own
// step count, so Gaussians added later get a proper bias correction.
class GaussianAdam {
 public:
  explicit GaussianAdam(const AdamConfig& config = {}) : config_(config) {}

  // Applies one step to every Gaussian, with every learning rate times `lr_scale`. Throws
  // splat::Error if the gradient layout differs from the map or the map size differs from the
  // optimizer state.
  // With a pool, ranges of Gaussians step on its threads (the same result).
  void step(splat::Gaussians& map, const splat::GaussianGrads& grads, double lr_scale = 1,
            splat::ThreadPool* pool = nullptr);
  // `n` new Gaussians at the end of the map, with zero moments.
  void append(std::size_t n, int sh_degree);
  // Keeps the Gaussians where keep[i] != 0, in order (the caller compacts the map the same way).
  void remove(std::span<const uint8_t> keep);

  // Everything a later step depends on, for checkpoints.
  struct State {
    splat::Gaussians m, v;
    std::vector<uint32_t> steps;
  };
  State state() const { return {m_, v_, steps_}; }
  // Throws splat::Error if the moments and step counts disagree in size.
  void restore(State state);

  std::size_t size() const { return steps_.size(); }
  const splat::Gaussians& first_moment() const { return m_; }
  const splat::Gaussians& second_moment() const { return v_; }
  const std::vector<uint32_t>& steps() const { return steps_; }
  AdamConfig& config() { return config_; }

 private:
  void ensure_layout(const splat::Gaussians& map);
  AdamConfig config_;
  splat::Gaussians m_, v_;
  std::vector<uint32_t> steps_;
  std::vector<double> beta1_powers_, beta2_powers_;  // beta^t for t = 0, 1, ...
};

// Compacts a map in place: keeps the Gaussians where keep[i] != 0, in order.
void remove_gaussians(splat::Gaussians& map, std::span<const uint8_t> keep);

}  // namespace mapping
