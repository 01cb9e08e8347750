#pragma once
#include <cstddef>
#include <span>
#include <string_view>
#include <vector>

#include "splat/thread_pool.h"

namespace splat {

// Number of spherical-harmonics coefficients per colour channel for a degree in 0..3.
constexpr int sh_coeff_count(int degree) { return (degree + 1) * (degree + 1); }
inline constexpr int kMaxShDegree = 3;

// A map of 3D Gaussians, stored as flat row-major arrays. Scalar is float for rendering and
// double for gradient checks. The same struct holds gradients (GaussianGradsT), field for field.
template <typename Scalar>
struct GaussiansT {
  std::vector<Scalar> means;           // [N, 3] world frame, metres
  std::vector<Scalar> log_scales;      // [N, 3] log of the standard deviations along the axes
  std::vector<Scalar> rotations;       // [N, 4] w, x, y, z; normalized on use
  std::vector<Scalar> opacity_logits;  // [N] opacity = sigmoid(logit)
  std::vector<Scalar> sh;              // [N, K, 3], K = (sh_degree + 1)^2, index 0 = DC
  int sh_degree = 0;

  std::size_t size() const { return opacity_logits.size(); }
  bool empty() const { return opacity_logits.empty(); }
  // Resizes every array for n Gaussians (new entries are zero).
  void resize(std::size_t n);
};
using Gaussians = GaussiansT<float>;
template <typename Scalar>
using GaussianGradsT = GaussiansT<Scalar>;
using GaussianGrads = GaussianGradsT<float>;

// Parameter groups, in the order of the fields above; used to iterate over fields uniformly.
enum class ParamGroup { kMeans, kLogScales, kRotations, kOpacityLogits, kSh };
inline constexpr ParamGroup kAllParamGroups[] = {ParamGroup::kMeans, ParamGroup::kLogScales,
                                                 ParamGroup::kRotations,
                                                 ParamGroup::kOpacityLogits, ParamGroup::kSh};
const char* param_group_name(ParamGroup group);
// Floats per Gaussian in a group (the SH width depends on the degree).
int param_group_width(ParamGroup group, int sh_degree);
template <typename Scalar>
std::vector<Scalar>& param_group(GaussiansT<Scalar>& g, ParamGroup group);
template <typename Scalar>
const std::vector<Scalar>& param_group(const GaussiansT<Scalar>& g, ParamGroup group);

// Non-owning view of a map; what the rasterizer takes.
template <typename Scalar>
struct GaussiansViewT {
  std::span<const Scalar> means;
  std::span<const Scalar> log_scales;
  std::span<const Scalar> rotations;
  std::span<const Scalar> opacity_logits;
  std::span<const Scalar> sh;
  int sh_degree = 0;

  GaussiansViewT() = default;
  GaussiansViewT(const GaussiansT<Scalar>& g)  // NOLINT: implicit on purpose, views are cheap
      : means(g.means),
        log_scales(g.log_scales),
        rotations(g.rotations),
        opacity_logits(g.opacity_logits),
        sh(g.sh),
        sh_degree(g.sh_degree) {}
  std::size_t size() const { return opacity_logits.size(); }
};
using GaussiansView = GaussiansViewT<float>;

// Checks that every array has the length N implies and that sh_degree is in 0..3.
// Throws splat::Error naming `where`, the field, the expected and the actual length.
template <typename Scalar>
void validate_sizes(const GaussiansViewT<Scalar>& g, std::string_view where);

// validate_sizes, then checks every value is finite (on `pool` where given: a map is checked on every
// render). Throws naming the field and the Gaussian.
template <typename Scalar>
void validate(const GaussiansViewT<Scalar>& g, std::string_view where, ThreadPool* pool = nullptr);

}  // namespace splat
