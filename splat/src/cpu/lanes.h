// Rows of a 16x16 tile as vector values (GCC vector extensions) and the few per-lane
// operations GCC does not provide on them, with single AVX-512 instructions where available.
// Every helper also takes plain scalars, so code written once serves one pixel or a row.
#pragma once
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <type_traits>

#if defined(__AVX512F__)
#include <immintrin.h>
#endif

#include "shader_io.h"

namespace splat::cpu {

inline constexpr int kRowLanes = static_cast<int>(io::kTileSize);

// One tile row of 16 pixels as one vector value (GCC vector extension). The forward pass keeps
// its rows' compositing state in registers while it walks the splats that reach them.
template <typename T>
struct RowOf;
template <>
struct RowOf<float> {
  typedef float type __attribute__((vector_size(kRowLanes * sizeof(float))));
  typedef int32_t mask __attribute__((vector_size(kRowLanes * sizeof(float))));
};
template <>
struct RowOf<double> {
  typedef double type __attribute__((vector_size(kRowLanes * sizeof(double))));
  typedef int64_t mask __attribute__((vector_size(kRowLanes * sizeof(double))));
};
template <typename T>
using Row = typename RowOf<T>::type;
// Integer lanes as wide as T's: comparisons give all ones (true) or zero.
template <typename T>
using RowMaskOf = typename RowOf<T>::mask;
using RowInt = RowMaskOf<float>;

using RowUint = uint32_t __attribute__((vector_size(kRowLanes * sizeof(uint32_t))));

// floor, round to nearest, max and p 2^n for float lanes, scalar or row; with AVX-512 one
// instruction each.
inline float floor_lanes(float x) { return std::floor(x); }
inline float round_lanes(float x) { return std::nearbyint(x); }  // ties to even: we never change the rounding mode
inline float max_lanes(float x, float lo) { return x < lo ? lo : x; }
inline float scale_by_pow2(float p, float n) {  // n integral, 2^n normal
  return p * std::bit_cast<float>((static_cast<int32_t>(n) + 127) << 23);
}
#if defined(__AVX512F__)
// The masked forms with every lane set: the same instructions, but GCC 12 warns that the
// unmasked ones read an undefined source (its bug 105593) once their inputs are constants.
inline constexpr __mmask16 kAllLanes = 0xFFFF;
inline Row<float> floor_lanes(Row<float> x) {
  return reinterpret_cast<Row<float>>(
      _mm512_mask_roundscale_ps(reinterpret_cast<__m512>(x), kAllLanes, reinterpret_cast<__m512>(x), _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC));
}
inline Row<float> scale_by_pow2(Row<float> p, Row<float> n) {
  return reinterpret_cast<Row<float>>(_mm512_mask_scalef_ps(reinterpret_cast<__m512>(p), kAllLanes, reinterpret_cast<__m512>(p), reinterpret_cast<__m512>(n)));
}
inline Row<float> round_lanes(Row<float> x) {
  return reinterpret_cast<Row<float>>(
      _mm512_mask_roundscale_ps(reinterpret_cast<__m512>(x), kAllLanes, reinterpret_cast<__m512>(x), _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC));
}
inline Row<float> max_lanes(Row<float> x, float lo) {  // the compare-and-select below is two
  return reinterpret_cast<Row<float>>(_mm512_mask_max_ps(reinterpret_cast<__m512>(x), kAllLanes, reinterpret_cast<__m512>(x), _mm512_set1_ps(lo)));
}
#else
inline Row<float> floor_lanes(Row<float> x) {  // exact for |x| < 2^23, as the range below keeps it
  const Row<float> cut = __builtin_convertvector(__builtin_convertvector(x, RowInt), Row<float>);
  return cut > x ? cut - 1 : cut;
}
inline Row<float> scale_by_pow2(Row<float> p, Row<float> n) {
  return p * reinterpret_cast<Row<float>>((__builtin_convertvector(n, RowInt) + 127) << 23);
}
inline Row<float> round_lanes(Row<float> x) {  // ties to even, as the AVX-512 form and GLSL's roundEven
  Row<float> r;
  for (int k = 0; k < kRowLanes; ++k) r[k] = std::nearbyint(x[k]);
  return r;
}
inline Row<float> max_lanes(Row<float> x, float lo) { return x < lo ? lo : x; }
#endif

// a b + c with one rounding, scalar or row. The compositing sources are built with
// -ffp-contract=off, so the maths both backends share (shaders/composite.glsl) fuses exactly
// where these are written, and nowhere else, whatever the compiler or target.
inline float fma_lanes(float a, float b, float c) { return std::fma(a, b, c); }
inline double fma_lanes(double a, double b, double c) { return std::fma(a, b, c); }
// A row as it is, or a scalar in every lane.
template <typename T, typename A>
inline Row<T> as_row(const A& a) {
  if constexpr (std::is_arithmetic_v<A>) {
    return T(a) - Row<T>{};  // x - 0 is x for every x, -0 included: a plain broadcast
  } else {
    return a;
  }
}
template <typename T, typename A, typename B, typename C>
inline Row<T> fma_rows(const A& a, const B& b, const C& c) {
  const Row<T> ra = as_row<T>(a), rb = as_row<T>(b), rc = as_row<T>(c);
#if defined(__AVX512F__)
  if constexpr (std::is_same_v<T, float>) {
    return reinterpret_cast<Row<float>>(
        _mm512_fmadd_ps(reinterpret_cast<__m512>(ra), reinterpret_cast<__m512>(rb), reinterpret_cast<__m512>(rc)));
  }
#endif
  Row<T> r;
  for (int k = 0; k < kRowLanes; ++k) r[k] = std::fma(ra[k], rb[k], rc[k]);
  return r;
}
// Any mix of a row and scalars: the row's type decides.
template <typename A, typename B, typename C>
  requires(!(std::is_arithmetic_v<A> && std::is_arithmetic_v<B> && std::is_arithmetic_v<C>))
inline auto fma_lanes(const A& a, const B& b, const C& c) {
  using R = decltype(a * b + c);
  using T = std::remove_cvref_t<decltype(R{}[0])>;
  return fma_rows<T>(a, b, c);
}

inline double floor_lanes(double x) { return std::floor(x); }
inline Row<double> floor_lanes(const Row<double>& x) {
  Row<double> r;
  for (int k = 0; k < kRowLanes; ++k) r[k] = std::floor(x[k]);
  return r;
}
template <typename V>
inline V ceil_lanes(const V& x) {
  return -floor_lanes(-x);
}

inline float sqrt_lanes(float x) { return std::sqrt(x); }
inline double sqrt_lanes(double x) { return std::sqrt(x); }
#if defined(__AVX512F__)
inline Row<float> sqrt_lanes(const Row<float>& x) {
  return reinterpret_cast<Row<float>>(_mm512_sqrt_ps(reinterpret_cast<__m512>(x)));
}
#else
inline Row<float> sqrt_lanes(const Row<float>& x) {
  Row<float> r;
  for (int k = 0; k < kRowLanes; ++k) r[k] = std::sqrt(x[k]);
  return r;
}
#endif
inline Row<double> sqrt_lanes(const Row<double>& x) {
  Row<double> r;
  for (int k = 0; k < kRowLanes; ++k) r[k] = std::sqrt(x[k]);
  return r;
}

// std::clamp's result, lane by lane.
template <typename V, typename B>
inline V clamp_lanes(const V& v, B lo, B hi) {
  return v < lo ? V{} + lo : (hi < v ? V{} + hi : v);
}

// Stores a row's first `count` lanes (a whole row in one vector store where it fits the image).
template <typename Out, typename Lanes>
inline void store_row(Out* out, const Lanes& row, int count) {
  static_assert(sizeof(Lanes) == kRowLanes * sizeof(Out));
  std::memcpy(out, &row, count == kRowLanes ? sizeof(Lanes) : static_cast<std::size_t>(count) * sizeof(Out));
}

template <typename M>
inline bool any_lane(const M& mask) {
  for (int x = 0; x < kRowLanes; ++x)
    if (mask[x]) return true;
  return false;
}
#if defined(__AVX512F__)
// Tests into mask registers; GCC 12 makes the loop above a long chain of extracts.
template <>
inline bool any_lane(const RowMaskOf<float>& mask) {
  const __m512i lanes = reinterpret_cast<__m512i>(mask);
  return _mm512_test_epi32_mask(lanes, lanes) != 0;
}
#endif

// Per-lane booleans of a row and the few operations the compositing passes need on them. In
// general a vector of all-ones or zero lanes, as GCC's comparisons give; for float rows with
// AVX-512 a mask register, which compares write and selects read directly (GCC 12 keeps
// vector masks in vector registers and converts at every use: a fifth of the forward's
// instructions).
template <typename T>
struct LaneMask {
  using M = RowMaskOf<T>;
  static M from_vector(M m) { return m; }
  static M ge(const Row<T>& a, T b, M within) { return (a >= b) & within; }  // a >= b where `within`
  static M gt(const Row<T>& a, T b, M within) { return (a > b) & within; }
  static M lt(const Row<T>& a, T b, M within) { return (a < b) & within; }
  static M int_less(int32_t a, M b) { return a < b; }  // lanes where a < b's integer lane
  static M and_not(M a, M b) { return a & ~b; }
  static M none() { return M{}; }
  static M all() { return ~M{}; }
  static Row<T> select(M m, const Row<T>& a, const Row<T>& b) { return m ? a : b; }
  static M select(M m, int32_t a, M b) { return m ? M{} + a : b; }
  static bool any(M m) { return any_lane(m); }
  static int count(M m) {
    int n = 0;
    for (int x = 0; x < kRowLanes; ++x) n += m[x] != 0;
    return n;
  }
};
#if defined(__AVX512F__)
template <>
struct LaneMask<float> {
  using M = __mmask16;
  static M from_vector(RowInt m) { return _mm512_test_epi32_mask(reinterpret_cast<__m512i>(m), reinterpret_cast<__m512i>(m)); }
  static M ge(const Row<float>& a, float b, M within) {
    return _mm512_mask_cmp_ps_mask(within, reinterpret_cast<__m512>(a), _mm512_set1_ps(b), _CMP_GE_OQ);
  }
  static M gt(const Row<float>& a, float b, M within) {
    return _mm512_mask_cmp_ps_mask(within, reinterpret_cast<__m512>(a), _mm512_set1_ps(b), _CMP_GT_OQ);
  }
  static M lt(const Row<float>& a, float b, M within) {
    return _mm512_mask_cmp_ps_mask(within, reinterpret_cast<__m512>(a), _mm512_set1_ps(b), _CMP_LT_OQ);
  }
  static M int_less(int32_t a, RowInt b) {
    return _mm512_cmpgt_epi32_mask(reinterpret_cast<__m512i>(b), _mm512_set1_epi32(a));
  }
  static M and_not(M a, M b) { return static_cast<M>(a & ~b); }
  static M none() { return 0; }
  static M all() { return 0xFFFF; }
  static Row<float> select(M m, const Row<float>& a, const Row<float>& b) {
    return reinterpret_cast<Row<float>>(_mm512_mask_blend_ps(m, reinterpret_cast<__m512>(b), reinterpret_cast<__m512>(a)));
  }
  static RowInt select(M m, int32_t a, RowInt b) {
    return reinterpret_cast<RowInt>(_mm512_mask_set1_epi32(reinterpret_cast<__m512i>(b), m, a));
  }
  static bool any(M m) { return m != 0; }
  static int count(M m) { return std::popcount(static_cast<unsigned>(m)); }
};
#endif

}  // namespace splat::cpu
