// What the compositing passes (forward, backward, pose JVP) share: the packed splat table, the
// per-pixel evaluation of a splat, a tile's geometry and a chunk of its splats.
#pragma once
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include "cpu/footprint.h"
#include "cpu/lanes.h"
#include "cpu/stages.h"
#include "shader_io.h"

namespace splat::cpu {

// Sizes a frame's output images to its camera and clears them: black, transmittance 1, no
// contributor. Every compositing forward pass starts here.
template <typename T>
void start_images(ForwardResultT<T>& f) {
  const std::size_t pixels = static_cast<std::size_t>(f.camera.width) * f.camera.height;
  f.width = f.camera.width;
  f.height = f.camera.height;
  f.rgb.assign(pixels * 3, 0);
  f.alpha.assign(pixels, 0);
  f.depth.assign(pixels, 0);
  f.depth_normalized.assign(pixels, 0);
  f.last_contributor.assign(pixels, 0);
  f.final_transmittance.assign(pixels, 1);
}

// Gradient slots per intersection in the backward pass (the order of shader_io.h).
enum Slot { kMx, kMy, kCa, kCb, kCc, kOpacity, kR, kG, kB, kZ, kSlots };
static_assert(kSlots == io::kGradSlots && kOpacity == io::kSlotOpacity && kZ == io::kSlotDepth);

// Every visible splat packed, indexed by Gaussian id (culled ones are never read). The table
// lives in the calling thread's storage and is reused by its next call: at 1M Gaussians it is
// 64 MB, which glibc would otherwise map, fault in and zero on every render. Each compositing
// function packs at its start and is done with it on return (the pool's workers never call one),
// so calls on one thread cannot overlap.
template <typename T>
const std::vector<Splat<T>>& pack_splats(const ForwardResultT<T>& f, ThreadPool& pool) {
  thread_local std::vector<Splat<T>> storage;
  std::vector<Splat<T>>& out = storage;  // the caller's: the name alone means each worker's own
  const std::size_t n = f.gaussians.size();
  if (out.size() < n) out.resize(n);
  constexpr std::size_t kChunk = 4096;
  pool.parallel_for((n + kChunk - 1) / kChunk, [&](std::size_t c) {
    for (std::size_t i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i) {
      if (f.radii[i * 2] > 0 || f.radii[i * 2 + 1] > 0) out[i] = pack_splat(f, i);
    }
  });
  return out;
}

// Splats are read in depth order, scattered over memory: fetch a few intersections ahead,
// within the tile's list [lo, hi). Always inlined: GCC 12 finds a separate function whose only
// effect is a prefetch "const" and deletes every call to it.
inline constexpr int64_t kPrefetchAhead = 8;
template <typename T>
[[gnu::always_inline]] inline void prefetch_splat(const Splat<T>* splats, const uint32_t* ids, int64_t s, int64_t lo,
                           int64_t hi) {
  if (s >= lo && s < hi) __builtin_prefetch(splats + ids[s]);
}

// Per-pixel evaluation shared by every pass: offset, Mahalanobis term and alpha. Loops over
// plain pixel arrays are written as single float selects (no &&, no bool lanes): GCC 12
// otherwise gives up vectorizing them.
template <typename T>
struct PixelEval {
  T dx, dy, sigma, gauss;
  T alpha;  // min(kAlphaMax, opacity * gauss), or 0 where sigma < 0 (never blended)
  T raw_alpha;  // opacity * gauss before the cap
};

// The per-pixel maths of compositing, the same in shaders/composite.glsl operation for
// operation: plain multiplies and adds, never fused (these sources are built with
// -ffp-contract=off, and the shader marks them precise), each correctly rounded on any CPU or
// Vulkan device, so the backends blend or skip a splat alike at the kAlphaMin and
// kTransmittanceMin cut-offs and agree on alpha bit for bit (tests/splat/
// composite_oracle_test.cpp). Fused multiply-adds would not do: lavapipe computes GLSL's fma()
// as a multiply and an add, NVIDIA as one operation. (This costs the CPU forward about 10%
// against fused exp and sigma. The colour and depth sums, which decide nothing, stay fused.)
//
// exp(x) for x <= 0 (a little above 0 is fine too). Float: 2^n e^r with n = x / ln 2 rounded to
// nearest (ties to even) and r = x - n ln 2 (Cephes' two-part ln 2, so r is exact), e^r by a
// degree-5 polynomial (minimax relative error 9e-8 on |r| <= ln(2) / 2, fitted by Lawson's
// iteration; about 2 ulp with rounding). Plain arithmetic, so it vectorizes (libm's expf does
// not without -ffast-math), for one value or a row. Double: std::exp, for gradient checks.
template <typename V>
inline V exp_nonpositive_float(V x) {
  x = max_lanes(x, -87.f);  // below, the result is under 2^-126 and would flush anyway
  const V n = round_lanes(x * 1.44269504088896341f);
  const V r = x - n * 0.693359375f + n * 2.12194440e-4f;
  V p = r * 8.290324360e-3f + 4.189795256e-2f;
  p = p * r + 1.666763574e-1f;
  p = p * r + 4.999915063e-1f;
  p = p * r + 9.999997020e-1f;
  p = p * r + 1.f;
  return scale_by_pow2(p, n);
}
inline float exp_nonpositive(float x) { return exp_nonpositive_float(x); }
inline Row<float> exp_nonpositive(Row<float> x) { return exp_nonpositive_float(x); }
inline double exp_nonpositive(double x) { return std::exp(x); }
inline Row<double> exp_nonpositive(const Row<double>& x) {
  Row<double> e;
  for (int k = 0; k < kTile; ++k) e[k] = std::exp(x[k]);
  return e;
}

// sigma = (a dx^2 + 2 b dx dy + c dy^2) / 2, as a quadratic in dx: dx (a/2 dx + b dy) + c/2 dy^2,
// with (dx, dy) the mean minus the pixel centre. The terms in dx alone are per column and those
// in dy alone per row, so a pass that evaluates one splat on many rows computes them once for
// all rows (SigmaTerms), leaving two operations per pixel.
template <typename T, typename V>
inline V half_a_dx(T ca, const V& dx) { return (T(0.5) * ca) * dx; }
template <typename T, typename V>
inline V b_dy(T cb, const V& dy) { return cb * dy; }
template <typename T, typename V>
inline V half_c_dy2(T cc, const V& dy) { return ((T(0.5) * cc) * dy) * dy; }
template <typename V, typename W>
inline V sigma_from(const V& dx, const V& a_dx, const W& b_dy, const W& c_dy2) { return dx * (a_dx + b_dy) + c_dy2; }

// One splat's sigma terms over a tile: dx per column, the dy terms per row.
template <typename T>
struct SigmaTerms {
  Row<T> dx, a_dx, b_dy, c_dy2;
  SigmaTerms() = default;
  SigmaTerms(const Splat<T>& s, const Row<T>& px, const Row<T>& py)
      : dx(s.mx - px), a_dx(half_a_dx(s.ca, dx)), b_dy(cpu::b_dy(s.cb, s.my - py)), c_dy2(half_c_dy2(s.cc, s.my - py)) {}
  Row<T> sigma(int row) const { return sigma_from(dx, a_dx, b_dy[row], c_dy2[row]); }
};

// gauss, alpha and the uncapped alpha from sigma.
template <typename T, typename V>
inline void eval_alpha(T opacity, PixelEval<V>& e) {
  // Where rounding makes sigma negative (at the mean) gauss is a little over 1, but such
  // pixels are never blended (gsplat skips sigma < 0).
  e.gauss = exp_nonpositive(-e.sigma);
  e.raw_alpha = e.sigma >= 0 ? opacity * e.gauss : T(0);
  e.alpha = e.raw_alpha < T(io::kAlphaMax) ? e.raw_alpha : T(io::kAlphaMax);
}
template <typename T, typename V>
inline void eval_alpha(const Splat<T>& s, PixelEval<V>& e) { eval_alpha(s.opacity, e); }

// One splat (2D mean, conic, opacity) at one pixel centre, or a row of them.
template <typename T, typename V>
inline PixelEval<V> eval_pixel(T mx, T my, T ca, T cb, T cc, T opacity, const V& px, T py) {
  PixelEval<V> e;
  const T dy = my - py;
  e.dx = mx - px;
  e.dy = V{} + dy;
  e.sigma = sigma_from(e.dx, half_a_dx(ca, e.dx), b_dy(cb, dy), half_c_dy2(cc, dy));
  eval_alpha(opacity, e);
  return e;
}

// V is T for one pixel or a row vector of T for a tile row; the row's py is one value.
template <typename T, typename V>
inline PixelEval<V> eval_pixel(const Splat<T>& s, const V& px, T py) {
  return eval_pixel(s.mx, s.my, s.ca, s.cb, s.cc, s.opacity, px, py);
}

// 1 where the forward pass blended sorted splat s into a pixel whose contributors end at
// `last`, else 0 (a float select, so the pixel loops stay vectorized).
template <typename T>
inline T blended(int32_t s, int32_t last, const PixelEval<T>& e) {  // int32: half the lanes of int64
  const T alpha_here = s < last ? e.alpha : T(0);
  return alpha_here >= T(io::kAlphaMin) ? T(1) : T(0);
}

// Lane x of a tile row as a value: its index, and its pixel centre's offset from the tile's
// corner (px = centre + x0, and the same row of values serves the rows' centres).
template <typename T>
struct TileLanes {
  Row<T> index{}, centre{};
  RowInt index_int{};
  TileLanes() {
    for (int x = 0; x < kTile; ++x) index[x] = T(x), index_int[x] = x;
    centre = index + T(0.5);
  }
};

struct TileGeometry {
  int x0, y0;          // first pixel of the tile
  int width, height;   // pixels of the tile inside the image
};

inline TileGeometry tile_geometry(int tile, int tiles_x, int image_w, int image_h) {
  const int x0 = (tile % tiles_x) * kTile, y0 = (tile / tiles_x) * kTile;
  return {x0, y0, std::min(kTile, image_w - x0), std::min(kTile, image_h - y0)};
}

// The compositing passes take a tile's splats in chunks of this many (bits of one word).
inline constexpr int kChunkSplats = 32;

// One chunk of a tile's splats: copies in tile-list order, and the rows each reaches, found
// for 16 splats at a time (the reach has two square roots; one splat at a time it was a
// quarter of the forward's compositing).
template <typename T>
struct Chunk {
  static_assert(kChunkSplats % kRowLanes == 0);
  alignas(64) Splat<T> splat[kChunkSplats];
  // The fields reach_rows reads, one array per field, so that lanes load as rows.
  alignas(64) T mx[kChunkSplats], my[kChunkSplats], half[kChunkSplats], s_top[kChunkSplats],
      cut[kChunkSplats], inv[kChunkSplats], b[kChunkSplats], det[kChunkSplats];
  int32_t first[kChunkSplats], end[kChunkSplats];  // the reached rows [first, end)
  int size = 0;

  void add(const Splat<T>& sp) {
    splat[size] = sp;
    mx[size] = sp.mx, my[size] = sp.my, half[size] = sp.half_v, s_top[size] = sp.u_top;
    cut[size] = sp.cut_c, inv[size] = sp.inv_cc, b[size] = sp.cb, det[size] = sp.det;
    ++size;
  }

  void find_rows(int tile_x0, int tile_y0) {
    using V = Row<T>;
    for (int j = size; j < kChunkSplats; ++j) {  // unused lanes reach nothing
      mx[j] = my[j] = s_top[j] = cut[j] = inv[j] = b[j] = det[j] = 0;
      half[j] = -1;
    }
    auto load = [](const T* p) {
      V v;
      std::memcpy(&v, p, sizeof v);
      return v;
    };
    for (int j = 0; j < size; j += kRowLanes) {
      const EllipseAxis<V> axis{load(half + j), load(s_top + j), load(cut + j), load(inv + j), load(b + j), load(det + j)};
      const RowReach<V> rows = reach_rows(axis, load(mx + j), load(my + j), T(tile_x0), T(tile_y0));
      const RowInt row_first = __builtin_convertvector(rows.first, RowInt), row_end = __builtin_convertvector(rows.end, RowInt);
      std::memcpy(first + j, &row_first, sizeof row_first);
      std::memcpy(end + j, &row_end, sizeof row_end);
    }
  }
};

}  // namespace splat::cpu
