#include "splat/gaussians.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "splat/error.h"

namespace splat {

template <typename Scalar>
void GaussiansT<Scalar>::resize(std::size_t n) {
  means.resize(n * 3);
  log_scales.resize(n * 3);
  rotations.resize(n * 4);
  opacity_logits.resize(n);
  sh.resize(n * sh_coeff_count(sh_degree) * 3);
}

const char* param_group_name(ParamGroup group) {
  switch (group) {
    case ParamGroup::kMeans: return "means";
    case ParamGroup::kLogScales: return "log_scales";
    case ParamGroup::kRotations: return "rotations";
    case ParamGroup::kOpacityLogits: return "opacity_logits";
    case ParamGroup::kSh: return "sh";
  }
  return "?";
}

int param_group_width(ParamGroup group, int sh_degree) {
  switch (group) {
    case ParamGroup::kMeans: return 3;
    case ParamGroup::kLogScales: return 3;
    case ParamGroup::kRotations: return 4;
    case ParamGroup::kOpacityLogits: return 1;
    case ParamGroup::kSh: return sh_coeff_count(sh_degree) * 3;
  }
  return 0;
}

namespace {
// The field of a group, for maps and views alike (they share field names).
template <typename Map>
auto& group_field(Map& g, ParamGroup group) {
  switch (group) {
    case ParamGroup::kMeans: return g.means;
    case ParamGroup::kLogScales: return g.log_scales;
    case ParamGroup::kRotations: return g.rotations;
    case ParamGroup::kOpacityLogits: return g.opacity_logits;
    case ParamGroup::kSh: return g.sh;
  }
  return g.means;
}
}  // namespace

template <typename Scalar>
std::vector<Scalar>& param_group(GaussiansT<Scalar>& g, ParamGroup group) {
  return group_field(g, group);
}

template <typename Scalar>
const std::vector<Scalar>& param_group(const GaussiansT<Scalar>& g, ParamGroup group) {
  return param_group(const_cast<GaussiansT<Scalar>&>(g), group);
}


template <typename Scalar>
void validate_sizes(const GaussiansViewT<Scalar>& g, std::string_view where) {
  if (g.sh_degree < 0 || g.sh_degree > kMaxShDegree) {
    throw Error(std::string(where) + ": sh_degree is " + std::to_string(g.sh_degree) +
                ", expected 0..3");
  }
  const std::size_t n = g.size();
  for (ParamGroup group : kAllParamGroups) {
    const std::size_t width = static_cast<std::size_t>(param_group_width(group, g.sh_degree));
    const std::size_t got = group_field(g, group).size();
    if (got != width * n) {
      throw Error(std::string(where) + ": " + param_group_name(group) + " has " +
                  std::to_string(got) + " values, expected " + std::to_string(width) + "*N = " +
                  std::to_string(width * n) + " (N = " + std::to_string(n) +
                  " from opacity_logits)");
    }
  }
}

template <typename Scalar>
void validate(const GaussiansViewT<Scalar>& g, std::string_view where, ThreadPool* pool) {
  validate_sizes(g, where);
  for (ParamGroup group : kAllParamGroups) {
    const auto values = group_field(g, group);
    const std::size_t width = static_cast<std::size_t>(param_group_width(group, g.sh_degree));
    // First a check that vectorizes (x - x is 0 unless x is infinite or NaN), then the search.
    constexpr std::size_t kChunk = 1 << 16;
    std::vector<int> chunk_finite((values.size() + kChunk - 1) / kChunk, 1);
    parallel_for(pool, chunk_finite.size(), [&](std::size_t c) {
      int finite = 1;
      const std::size_t end = std::min(values.size(), (c + 1) * kChunk);
#pragma omp simd reduction(& : finite)
      for (std::size_t i = c * kChunk; i < end; ++i) finite &= (values[i] - values[i] == 0);
      chunk_finite[c] = finite;
    });
    if (std::all_of(chunk_finite.begin(), chunk_finite.end(), [](int f) { return f != 0; })) continue;
    for (std::size_t i = 0; i < values.size(); ++i) {
      if (!std::isfinite(values[i])) {
        throw Error(std::string(where) + ": " + param_group_name(group) + " of Gaussian " +
                    std::to_string(i / width) + " is " + std::to_string(values[i]) +
                    ", expected a finite value");
      }
    }
  }
}

#define GSLAM_INSTANTIATE(Scalar)                                                           \
  template struct GaussiansT<Scalar>;                                                       \
  template std::vector<Scalar>& param_group(GaussiansT<Scalar>&, ParamGroup);               \
  template const std::vector<Scalar>& param_group(const GaussiansT<Scalar>&, ParamGroup);   \
  template void validate_sizes(const GaussiansViewT<Scalar>&, std::string_view);           \
  template void validate(const GaussiansViewT<Scalar>&, std::string_view, ThreadPool*);
GSLAM_INSTANTIATE(float)
GSLAM_INSTANTIATE(double)
#undef GSLAM_INSTANTIATE

}  // namespace splat
