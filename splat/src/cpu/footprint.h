// A splat's footprint on screen: the packed parameters the compositing loops read, and the rows
// of a tile where its alpha can reach kAlphaMin.
#pragma once
#include <cmath>

#include "cpu/lanes.h"
#include "splat/rasterizer.h"
#include "shader_io.h"

namespace splat::cpu {

inline constexpr int kTile = static_cast<int>(io::kTileSize);
inline constexpr int kTilePixels = kTile * kTile;

// One splat's screen parameters and culling bounds, packed so that an intersection costs one
// memory access: tiles read splats in depth order, which scatters across the per-Gaussian arrays.
template <typename T>
struct alignas(64) Splat {
  T mx, my;       // 2D mean, pixels
  T ca, cb, cc;   // conic
  T opacity;
  T r, g, b, z;   // colour and camera depth
  // alpha >= kAlphaMin needs sigma <= ln(opacity / kAlphaMin); `limit` adds kCullSlack to that.
  // sigma <= limit is an ellipse reaching +-half_v rows above and below the mean, with its top
  // point at u = u_top; reach_rows also needs 2 c limit, det and 1 / c (no divide per tile).
  T limit, det, half_v, u_top, cut_c, inv_cc;
};
static_assert(sizeof(Splat<float>) == 64, "one cache line per splat");

// Culling keeps pixels down to alpha = exp(-kCullSlack) kAlphaMin, so that rounding in the
// bounds below can never cull a pixel the pixel loops would blend.
inline constexpr double kCullSlack = 0.05;

template <typename T>
Splat<T> pack_splat(const ForwardResultT<T>& f, std::size_t id) {
  Splat<T> sp{};
  sp.mx = f.means2d[id * 2];
  sp.my = f.means2d[id * 2 + 1];
  sp.ca = f.conics[id * 3];
  sp.cb = f.conics[id * 3 + 1];
  sp.cc = f.conics[id * 3 + 2];
  sp.opacity = f.opacities[id];
  sp.r = f.colors[id * 3];
  sp.g = f.colors[id * 3 + 1];
  sp.b = f.colors[id * 3 + 2];
  sp.z = f.depths[id];
  sp.limit = std::log(sp.opacity / T(io::kAlphaMin)) + T(kCullSlack);
  sp.det = sp.ca * sp.cc - sp.cb * sp.cb;
  // 0.5 d^T Q d <= limit reaches |dv| <= sqrt(2 limit (Q^-1)_yy); -1 marks "reaches nothing".
  const bool reaches = sp.limit > 0 && sp.det > 0 && sp.ca > 0 && sp.cc > 0;
  sp.half_v = reaches ? std::sqrt(2 * sp.limit * sp.ca / sp.det) : T(-1);
  sp.u_top = reaches ? -sp.cb * sp.half_v / sp.ca : T(0);
  sp.cut_c = 2 * sp.cc * sp.limit;
  sp.inv_cc = reaches ? 1 / sp.cc : T(0);
  return sp;
}

// The ellipse sigma <= limit in offsets (u, v) from the mean, sigma = (a u^2 + 2 b u v + c v^2) / 2,
// seen along one axis w (v; u would swap a and c), the other axis being s:
//   half    largest w on the ellipse (negative: the ellipse is empty), reached at s = s_top;
//   cut     2 limit times the conic's w^2 coefficient, inv its inverse; b and det of the conic.
// The w-range of the ellipse inside the strip s0 <= s <= s1 is one interval (the intersection
// is convex): up to the top point where it lies in the strip, else up to where the nearer
// strip edge cuts the ellipse, at w = (-b s + sqrt(cut - det s^2)) inv; likewise down to the
// bottom point (-s_top, -half).
template <typename V>
struct EllipseAxis {
  V half, s_top, cut, inv, b, det;
};

// V is T for one splat or a row of T for 16 splats at once; the result is true, or all ones,
// where the strip meets the ellipse (w_lo and w_hi are meaningless elsewhere).
template <typename V>
inline auto strip_extent(const EllipseAxis<V>& e, const V& s0, const V& s1, V& w_lo, V& w_hi) {
  // Selects, not branches: they mispredict.
  const V s_hi = clamp_lanes(e.s_top, s0, s1), s_lo = clamp_lanes(-e.s_top, s0, s1);
  const auto top_in = s_hi == e.s_top, bottom_in = s_lo == -e.s_top;
  const V disc_hi = e.cut - e.det * s_hi * s_hi, disc_lo = e.cut - e.det * s_lo * s_lo;
  const V cut_hi = (-e.b * s_hi + sqrt_lanes(disc_hi < 0 ? V{} : disc_hi)) * e.inv;
  const V cut_lo = (-e.b * s_lo - sqrt_lanes(disc_lo < 0 ? V{} : disc_lo)) * e.inv;
  w_hi = top_in ? e.half : cut_hi;
  w_lo = bottom_in ? -e.half : cut_lo;
  return e.half >= 0 && (top_in || disc_hi >= 0) && (bottom_in || disc_lo >= 0);
}

// The splat's ellipse along v (rows), from the packed fields.
template <typename T>
inline EllipseAxis<T> row_axis(const Splat<T>& sp) {
  return {sp.half_v, sp.u_top, sp.cut_c, sp.inv_cc, sp.cb, sp.det};
}

// The tile rows [first, end) in which some pixel can reach alpha >= kAlphaMin, as whole
// numbers in V (first >= end: none); the compositing loops evaluate those rows whole (16
// pixels, one vector), which equals evaluating the tile. Row y (centre tile_y0 + y + 0.5) is
// inside when my + v_lo <= centre <= my + v_hi.
template <typename V>
struct RowReach {
  V first, end;
};
template <typename V, typename T>
inline RowReach<V> reach_rows(const EllipseAxis<V>& axis, const V& mx, const V& my, T tile_x0, T tile_y0) {
  const V u0 = (tile_x0 + T(0.5)) - mx;
  V v_lo{}, v_hi{};
  const auto hit = strip_extent(axis, u0, u0 + T(kTile - 1), v_lo, v_hi);
  // Clamped before rounding, so that huge extents stay in range of any rounding method.
  const V lo = clamp_lanes(my + v_lo - tile_y0 - T(0.5), T(-1), T(kTile + 1));
  const V hi = clamp_lanes(my + v_hi - tile_y0 - T(0.5), T(-1), T(kTile + 1));
  return {hit ? clamp_lanes(ceil_lanes(lo), T(0), T(kTile)) : V{},
          hit ? clamp_lanes(floor_lanes(hi) + 1, T(0), T(kTile)) : V{}};
}

// The same for one packed splat, as indices.
struct IndexRange {
  int first = 0, end = 0;
};
template <typename T>
inline IndexRange reach_rows(const Splat<T>& sp, int tile_x0, int tile_y0) {
  if (sp.half_v < 0) return {};  // reaches nothing: spares the square roots
  const RowReach<T> r = reach_rows(row_axis(sp), sp.mx, sp.my, T(tile_x0), T(tile_y0));
  return {static_cast<int>(r.first), static_cast<int>(r.end)};
}

}  // namespace splat::cpu
