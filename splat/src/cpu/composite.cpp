// Front-to-back alpha compositing per 16x16 tile, and its backward pass. Within a tile the loop
// runs splat by splat over the tile's pixels, so the pixel loop vectorizes.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <iterator>

#include "cpu/footprint.h"
#include "cpu/lanes.h"
#include "cpu/stages.h"
#include "shader_io.h"

namespace splat::cpu {
namespace {

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

// Per-pixel evaluation shared by forward and backward: offset, Mahalanobis term and alpha.
// The pixel loops below are written as single float selects (no &&, no bool lanes): GCC 12
// otherwise gives up vectorizing them.
template <typename T>
struct PixelEval {
  T dx, dy, sigma, gauss;
  T alpha;  // min(kAlphaMax, opacity * gauss), or 0 where sigma < 0 (never blended)
  T raw_alpha;  // opacity * gauss before the cap
};

// exp(x) for x <= 0. Float: Cephes' range reduction and minimax polynomial (~2 ulp), written as
// plain arithmetic so that it vectorizes (libm's expf does not without -ffast-math), for one
// value or a row. Double: std::exp, for gradient checks.
template <typename V>
inline V exp_nonpositive_float(V x) {
  x = x < -87.f ? -87.f : x;  // below this the result is under 2^-126 and would flush anyway
  const V n = floor_lanes(x * 1.44269504088896341f + 0.5f);
  const V r = x - n * 0.693359375f + n * 2.12194440e-4f;  // x - n ln2, in two parts
  V p = r * 1.9875691500e-4f + 1.3981999507e-3f;
  p = p * r + 8.3334519073e-3f;
  p = p * r + 4.1665795894e-2f;
  p = p * r + 1.6666665459e-1f;
  p = p * r + 5.0000001201e-1f;
  p = p * r * r + r + 1.f;
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

// V is T for one pixel or a row vector of T for a tile row; the row's py is one value.
template <typename T, typename V>
inline PixelEval<V> eval_pixel(const Splat<T>& s, const V& px, T py) {
  PixelEval<V> e;
  const T dy = s.my - py;
  e.dx = s.mx - px;
  e.dy = V{} + dy;
  // sigma = (a dx^2 + 2 b dx dy + c dy^2) / 2, as a quadratic in dx whose coefficients are
  // per row: two fused multiply-adds per pixel.
  e.sigma = e.dx * (T(0.5) * s.ca * e.dx + s.cb * dy) + T(0.5) * s.cc * dy * dy;
  e.gauss = exp_nonpositive(-(e.sigma < 0 ? T(0) : e.sigma));
  e.raw_alpha = e.sigma >= 0 ? s.opacity * e.gauss : T(0);
  e.alpha = e.raw_alpha < T(io::kAlphaMax) ? e.raw_alpha : T(io::kAlphaMax);
  return e;
}

// 1 where the forward pass blended sorted splat s into a pixel whose contributors end at
// `last`, else 0 (a float select, so the pixel loops stay vectorized).
template <typename T>
inline T blended(int32_t s, int32_t last, const PixelEval<T>& e) {  // int32: half the lanes of int64
  const T alpha_here = s < last ? e.alpha : T(0);
  return alpha_here >= T(io::kAlphaMin) ? T(1) : T(0);
}

// Whether any of a row's lanes is positive. AVX-512 tests all 16 floats at once into a mask;
// GCC 12 makes a max reduction over the pixel loop into a long chain of shuffles instead.
template <typename T>
inline bool any_positive(const T (&v)[kTile]) {
  return std::any_of(std::begin(v), std::end(v), [](T x) { return x > 0; });
}
#if defined(__AVX512F__)
template <>
inline bool any_positive(const float (&v)[kTile]) {
  static_assert(kTile == 16);
  return _mm512_cmp_ps_mask(_mm512_load_ps(v), _mm512_setzero_ps(), _CMP_GT_OQ) != 0;
}
#endif

struct TileGeometry {
  int x0, y0;          // first pixel of the tile
  int width, height;   // pixels of the tile inside the image
};

TileGeometry tile_geometry(int tile, int tiles_x, int image_w, int image_h) {
  const int x0 = (tile % tiles_x) * kTile, y0 = (tile / tiles_x) * kTile;
  return {x0, y0, std::min(kTile, image_w - x0), std::min(kTile, image_h - y0)};
}

}  // namespace

// The forward pass takes a tile's splats in chunks: it copies out those of a chunk that reach
// the tile, with a bit per row saying which rows each one reaches; then each block of rows
// walks its bits. Two rows per block give the out-of-order core two independent dependency
// chains (transmittance runs from splat to splat), for the price of evaluating a splat on a
// row it may miss: 2% faster than one row, 20% faster than four (100K donut, 2 cores).
inline constexpr int kChunkSplats = 32;
inline constexpr int kBlockRows = 2;
inline constexpr int kBlocks = kTile / kBlockRows;

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

template <typename T>
void composite_forward(ForwardResultT<T>& f, ThreadPool& pool) {
  using V = Row<T>;
  using RowMask = RowMaskOf<T>;
  const int w = f.camera.width, h = f.camera.height;
  const std::size_t pixels = static_cast<std::size_t>(w) * h;
  f.width = w;
  f.height = h;
  f.rgb.assign(pixels * 3, 0);
  f.alpha.assign(pixels, 0);
  f.depth.assign(pixels, 0);
  f.depth_normalized.assign(pixels, 0);
  f.last_contributor.assign(pixels, 0);
  f.final_transmittance.assign(pixels, 1);
  const T bg[3] = {T(f.settings.background[0]), T(f.settings.background[1]),
                   T(f.settings.background[2])};
  const std::vector<Splat<T>>& splats = pack_splats(f, pool);
  V lane{};
  RowInt row_index{};
  for (int x = 0; x < kTile; ++x) lane[x] = T(x), row_index[x] = x;

  pool.parallel_for(static_cast<std::size_t>(f.tiles_x) * f.tiles_y, [&](std::size_t tile) {
    const TileGeometry geo = tile_geometry(static_cast<int>(tile), f.tiles_x, w, h);
    V trans[kTile], acc_r[kTile], acc_g[kTile], acc_b[kTile], acc_z[kTile];
    RowMask row_done[kTile];
    RowMask last[kTile];  // integer lanes as wide as T's
    int block_live[kBlocks] = {};  // pixels of each block still compositing
    for (int y = 0; y < kTile; ++y) {
      trans[y] = V{} + 1;
      acc_r[y] = acc_g[y] = acc_b[y] = acc_z[y] = V{};
      last[y] = RowMask{};
      // Pixels past the image edge start finished so they never hold the tile open.
      row_done[y] = (lane >= T(geo.width)) | (RowMask{} - (y >= geo.height));
      block_live[y / kBlockRows] += y < geo.height ? geo.width : 0;
    }
    int remaining = geo.width * geo.height;
    const V px = lane + (T(geo.x0) + T(0.5));
    Chunk<T> chunk;
    const Splat<T>* kept[kChunkSplats];  // the chunk's splats that reach a row, in order
    int32_t chunk_next_last[kChunkSplats];
    const uint32_t begin = f.tile_ranges[tile * 2], end = f.tile_ranges[tile * 2 + 1];
    for (uint32_t c = begin; c < end && remaining > 0; c += kChunkSplats) {
      chunk.size = 0;
      for (uint32_t s = c; s < std::min(end, c + kChunkSplats); ++s) {
        prefetch_splat(splats.data(), f.sorted_ids.data(), int64_t(s) + kPrefetchAhead, begin, end);
        chunk.add(splats[f.sorted_ids[s]]);
      }
      chunk.find_rows(geo.x0, geo.y0);
      RowInt row_bits{};  // bit k of row y: kept splat k reaches row y
      int count = 0;
      for (int j = 0; j < chunk.size; ++j) {
        // Written always, kept only if it reaches a row: whether it does is a coin toss (about
        // half of all intersections reach none), and a branch on it would mispredict.
        kept[count] = &chunk.splat[j];
        chunk_next_last[count] = static_cast<int32_t>(c + j + 1);
        row_bits |= (row_index >= chunk.first[j] && row_index < chunk.end[j]) ? int32_t(1u << count) : 0;
        count += chunk.first[j] < chunk.end[j];
      }
      for (int j = 0; j < kBlocks; ++j) {
        const int y0 = j * kBlockRows;
        uint32_t bits = 0;
        for (int q = 0; q < kBlockRows; ++q) bits |= static_cast<uint32_t>(row_bits[y0 + q]);
        if (block_live[j] == 0 || bits == 0) continue;
        V t[kBlockRows], r[kBlockRows], g[kBlockRows], b[kBlockRows], z[kBlockRows];
        T py[kBlockRows];
        RowMask done[kBlockRows], l[kBlockRows];
        for (int q = 0; q < kBlockRows; ++q) {
          t[q] = trans[y0 + q], r[q] = acc_r[y0 + q], g[q] = acc_g[y0 + q], b[q] = acc_b[y0 + q];
          z[q] = acc_z[y0 + q], done[q] = row_done[y0 + q], l[q] = last[y0 + q];
          py[q] = T(geo.y0 + y0 + q) + T(0.5);
        }
        for (; bits != 0; bits &= bits - 1) {
          const int k = std::countr_zero(bits);
          const Splat<T>& sp = *kept[k];
          RowMask stopped{};
#pragma GCC unroll 4
          for (int q = 0; q < kBlockRows; ++q) {
            const PixelEval<V> e = eval_pixel(sp, px, py[q]);
            const V next_t = t[q] * (1 - e.alpha);
            // Lanes where the splat blends into a still-compositing pixel: the pixel keeps
            // compositing or, where transmittance falls to the cut-off, stops without it.
            const RowMask blends = (e.alpha >= T(io::kAlphaMin)) & ~done[q];
            const RowMask keep = blends & (next_t > T(io::kTransmittanceMin));
            const RowMask stop = blends & ~keep;
            const V weight = keep ? e.alpha * t[q] : T(0);
            r[q] += weight * sp.r;
            g[q] += weight * sp.g;
            b[q] += weight * sp.b;
            z[q] += weight * sp.z;
            t[q] = keep ? next_t : t[q];
            l[q] = keep ? chunk_next_last[k] : l[q];
            done[q] |= stop;
            stopped |= stop;
          }
          if (!any_lane(stopped)) continue;  // pixels finish rarely: count only when one did
          int live_now = 0;
          for (int q = 0; q < kBlockRows; ++q)
            for (int x = 0; x < kTile; ++x) live_now += done[q][x] == 0;
          remaining -= block_live[j] - live_now;
          block_live[j] = live_now;
          if (live_now == 0) break;
        }
        for (int q = 0; q < kBlockRows; ++q) {
          trans[y0 + q] = t[q], acc_r[y0 + q] = r[q], acc_g[y0 + q] = g[q], acc_b[y0 + q] = b[q];
          acc_z[y0 + q] = z[q], row_done[y0 + q] = done[q], last[y0 + q] = l[q];
        }
      }
    }
    for (int y = 0; y < geo.height; ++y) {
      const std::size_t o = static_cast<std::size_t>(geo.y0 + y) * w + geo.x0;
      const V alpha = 1 - trans[y];
      const V red = acc_r[y] + trans[y] * bg[0], green = acc_g[y] + trans[y] * bg[1],
              blue = acc_b[y] + trans[y] * bg[2];
      store_row(&f.alpha[o], alpha, geo.width);
      store_row(&f.depth[o], acc_z[y], geo.width);
      store_row(&f.depth_normalized[o], alpha > 0 ? acc_z[y] / alpha : T(0), geo.width);
      store_row(&f.final_transmittance[o], trans[y], geo.width);
      store_row(&f.last_contributor[o], __builtin_convertvector(last[y], RowUint), geo.width);
      for (int x = 0; x < geo.width; ++x) {
        f.rgb[(o + x) * 3] = red[x];
        f.rgb[(o + x) * 3 + 1] = green[x];
        f.rgb[(o + x) * 3 + 2] = blue[x];
      }
    }
  });
}

template <typename T>
ScreenGrads<T> composite_backward(const ForwardResultT<T>& f, const ImageGradsT<T>& d_image,
                                  ThreadPool& pool, std::vector<T>& scratch) {
  const int w = f.width, h = f.height;
  const std::size_t n = f.gaussians.size();
  // Gradients per intersection: every intersection belongs to one tile, so tiles write disjoint
  // slots, and the per-Gaussian sum below runs in a fixed order. Only a tile's intersections
  // in front of its pixels' last contributors get gradients (often a third of them), so slots
  // are kept for those alone: tile t's sorted positions [begin, used_end) map to slots from
  // slot_start[t] on. Every kept slot is written below, so the reused buffer needs no clearing.
  const std::size_t tiles = static_cast<std::size_t>(f.tiles_x) * f.tiles_y;
  std::vector<uint32_t> used_end(tiles), slot_start(tiles + 1, 0);
  pool.parallel_for(tiles, [&](std::size_t tile) {
    const TileGeometry geo = tile_geometry(static_cast<int>(tile), f.tiles_x, w, h);
    uint32_t end = f.tile_ranges[tile * 2];
    for (int y = 0; y < geo.height; ++y)
      for (int x = 0; x < geo.width; ++x)
        end = std::max(end, f.last_contributor[static_cast<std::size_t>(geo.y0 + y) * w + (geo.x0 + x)]);
    used_end[tile] = end;
  });
  for (std::size_t t = 0; t < tiles; ++t) {
    slot_start[t + 1] = slot_start[t] + (used_end[t] - f.tile_ranges[t * 2]);
  }
  auto slot = [&](std::size_t tile, int64_t s) {
    return (slot_start[tile] + static_cast<std::size_t>(s - f.tile_ranges[tile * 2])) * kSlots;
  };
  std::vector<T>& isect = scratch;
  if (isect.size() < std::size_t(slot_start[tiles]) * kSlots) isect.resize(std::size_t(slot_start[tiles]) * kSlots);
  const T bg[3] = {T(f.settings.background[0]), T(f.settings.background[1]),
                   T(f.settings.background[2])};
  auto grad_at = [](const std::vector<T>& v, std::size_t i) { return v.empty() ? T(0) : v[i]; };
  const std::vector<Splat<T>>& splats = pack_splats(f, pool);
  using V = Row<T>;
  using RowMask = RowMaskOf<T>;

  V lane{};
  RowInt row_index{};
  for (int x = 0; x < kTile; ++x) lane[x] = T(x), row_index[x] = x;

  pool.parallel_for(static_cast<std::size_t>(f.tiles_x) * f.tiles_y, [&](std::size_t tile) {
    const TileGeometry geo = tile_geometry(static_cast<int>(tile), f.tiles_x, w, h);
    // Per pixel row: transmittance walking back to front, colour/depth accumulated behind the
    // current splat, upstream gradients and the alpha/background term T_final (dA - bg.dC).
    V trans[kTile], behind_r[kTile], behind_g[kTile], behind_b[kTile], behind_z[kTile],
        v_r[kTile], v_g[kTile], v_b[kTile], v_z[kTile], v_final[kTile];
    RowMask last[kTile];
    int32_t row_max_last[kTile];  // per row: one past the last splat any pixel used
    for (int y = 0; y < kTile; ++y) {
      trans[y] = V{} + 1;
      behind_r[y] = behind_g[y] = behind_b[y] = behind_z[y] = V{};
      v_r[y] = v_g[y] = v_b[y] = v_z[y] = v_final[y] = V{};
      last[y] = RowMask{};
      row_max_last[y] = 0;
      for (int x = 0; x < std::min(geo.width, y < geo.height ? kTile : 0); ++x) {
        const std::size_t o = static_cast<std::size_t>(geo.y0 + y) * w + (geo.x0 + x);
        trans[y][x] = f.final_transmittance[o];
        v_r[y][x] = grad_at(d_image.rgb, o * 3);
        v_g[y][x] = grad_at(d_image.rgb, o * 3 + 1);
        v_b[y][x] = grad_at(d_image.rgb, o * 3 + 2);
        v_z[y][x] = grad_at(d_image.depth, o);
        // rgb += T_final bg and alpha = 1 - T_final; dT_final/dalpha_j = -T_final / (1 - alpha_j).
        v_final[y][x] = trans[y][x] * (grad_at(d_image.alpha, o) -
                                       (bg[0] * v_r[y][x] + bg[1] * v_g[y][x] + bg[2] * v_b[y][x]));
        last[y][x] = static_cast<int32_t>(f.last_contributor[o]);
        row_max_last[y] = std::max<int32_t>(row_max_last[y], static_cast<int32_t>(last[y][x]));
      }
    }
    RowInt max_last{};
    for (int y = 0; y < kTile; ++y) max_last[y] = row_max_last[y];
    const V px = lane + (T(geo.x0) + T(0.5));
    // Back to front in chunks, as the forward pass goes front to back: chunk splat k (the k-th
    // from the back) reaches the rows of bit k, and its gradients add up per lane over the rows.
    Chunk<T> chunk;
    const Splat<T>* kept[kChunkSplats];  // the chunk's splats that reach a row, back to front
    int32_t chunk_pos[kChunkSplats];
    V chunk_grads[kChunkSplats][kSlots];
    const int32_t begin = static_cast<int32_t>(f.tile_ranges[tile * 2]);
    for (int32_t c = static_cast<int32_t>(used_end[tile]); c > begin; c -= kChunkSplats) {
      chunk.size = 0;
      for (int32_t s = c - 1; s >= std::max(begin, c - kChunkSplats); --s) {
        prefetch_splat(splats.data(), f.sorted_ids.data(), s - kPrefetchAhead, begin, s);
        chunk.add(splats[f.sorted_ids[s]]);
        std::fill_n(&isect[slot(tile, s)], kSlots, T(0));  // kept if it reaches no pixel
      }
      chunk.find_rows(geo.x0, geo.y0);
      RowInt row_bits{};
      int count = 0;
      for (int j = 0; j < chunk.size; ++j) {
        // Written always, kept only if it reaches a row a pixel composited it in.
        const int32_t s = c - 1 - j;
        kept[count] = &chunk.splat[j];
        chunk_pos[count] = s;
        const RowInt reached = row_index >= chunk.first[j] && row_index < chunk.end[j] && s < max_last;
        row_bits |= reached ? int32_t(1u << count) : 0;
        count += any_lane(reached);
      }
      for (int k = 0; k < count; ++k)
        for (int slot_k = 0; slot_k < kSlots; ++slot_k) chunk_grads[k][slot_k] = V{};
      for (int y = 0; y < kTile; ++y) {
        uint32_t bits = static_cast<uint32_t>(row_bits[y]);
        if (bits == 0) continue;
        const T py = T(geo.y0 + y) + T(0.5);
        V t_row = trans[y], br = behind_r[y], bgr = behind_g[y], bb = behind_b[y], bz = behind_z[y];
        const V vr = v_r[y], vg = v_g[y], vb = v_b[y], vz = v_z[y], vf = v_final[y];
        const RowMask l = last[y];
        for (; bits != 0; bits &= bits - 1) {
          const int k = std::countr_zero(bits);
          const Splat<T>& sp = *kept[k];
          const PixelEval<V> e = eval_pixel(sp, px, py);
          // Where the forward pass blended this splat: in front of the pixel's last one.
          const RowMask live = (chunk_pos[k] < l) & (e.alpha >= T(io::kAlphaMin));
          const V inv = live ? T(1) / (1 - e.alpha) : T(0);
          const V t = live ? t_row * inv : t_row;  // transmittance in front of it
          const V weight = live ? e.alpha * t : T(0);
          // dL/dalpha: own contribution minus what it hides behind, plus the T_final terms.
          const V v_alpha = (sp.r * t - br * inv) * vr + (sp.g * t - bgr * inv) * vg +
                            (sp.b * t - bb * inv) * vb + (sp.z * t - bz * inv) * vz + vf * inv;
          V* grads = chunk_grads[k];
          grads[kR] += weight * vr;
          grads[kG] += weight * vg;
          grads[kB] += weight * vb;
          grads[kZ] += weight * vz;
          br += weight * sp.r;
          bgr += weight * sp.g;
          bb += weight * sp.b;
          bz += weight * sp.z;
          t_row = t;
          // alpha = min(kAlphaMax, opacity * exp(-sigma)): no gradient where capped.
          const RowMask smooth = live & (e.raw_alpha < T(io::kAlphaMax));
          const V v_sigma = smooth ? -sp.opacity * e.gauss * v_alpha : T(0);
          grads[kOpacity] += smooth ? e.gauss * v_alpha : T(0);
          grads[kCa] += T(0.5) * e.dx * e.dx * v_sigma;
          grads[kCc] += T(0.5) * e.dy * e.dy * v_sigma;
          grads[kCb] += e.dx * e.dy * v_sigma;
          grads[kMx] += (sp.ca * e.dx + sp.cb * e.dy) * v_sigma;
          grads[kMy] += (sp.cc * e.dy + sp.cb * e.dx) * v_sigma;
        }
        trans[y] = t_row, behind_r[y] = br, behind_g[y] = bgr, behind_b[y] = bb, behind_z[y] = bz;
      }
      for (int k = 0; k < count; ++k) {
        T* out = &isect[slot(tile, chunk_pos[k])];
        for (int slot_k = 0; slot_k < kSlots; ++slot_k) {
          T sum = 0;
          for (int x = 0; x < kTile; ++x) sum += chunk_grads[k][slot_k][x];
          out[slot_k] = sum;
        }
      }
    }
  });

  ScreenGrads<T> g;
  g.means2d.assign(n * 2, 0);
  g.conics.assign(n * 3, 0);
  g.opacities.assign(n, 0);
  g.colors.assign(n * 3, 0);
  g.depths.assign(n, 0);
  // Each part sums the Gaussians of its id range, every one in sorted order, so the result does
  // not depend on how many parts there are.
  const std::size_t parts = static_cast<std::size_t>(pool.size());
  pool.parallel_for(parts, [&](std::size_t part) {
    const std::size_t id_begin = n * part / parts, id_end = n * (part + 1) / parts;
    for (std::size_t t = 0; t < tiles; ++t) {  // sorted order, skipping slots never kept
      for (int64_t s = f.tile_ranges[t * 2]; s < used_end[t]; ++s) {
        const std::size_t id = f.sorted_ids[static_cast<std::size_t>(s)];
        if (id < id_begin || id >= id_end) continue;
        const T* in = &isect[slot(t, s)];
        g.means2d[id * 2] += in[kMx];
        g.means2d[id * 2 + 1] += in[kMy];
        g.conics[id * 3] += in[kCa];
        g.conics[id * 3 + 1] += in[kCb];
        g.conics[id * 3 + 2] += in[kCc];
        g.opacities[id] += in[kOpacity];
        g.colors[id * 3] += in[kR];
        g.colors[id * 3 + 1] += in[kG];
        g.colors[id * 3 + 2] += in[kB];
        g.depths[id] += in[kZ];
      }
    }
  });
  return g;
}

template void composite_forward(ForwardResultT<float>&, ThreadPool&);
template void composite_forward(ForwardResultT<double>&, ThreadPool&);
template ScreenGrads<float> composite_backward(const ForwardResultT<float>&,
                                               const ImageGradsT<float>&, ThreadPool&,
                                               std::vector<float>&);
template ScreenGrads<double> composite_backward(const ForwardResultT<double>&,
                                                const ImageGradsT<double>&, ThreadPool&,
                                                std::vector<double>&);

template <typename T>
void composite_pose_jvp(const ForwardResultT<T>& f, const std::vector<T>& screen_jvp, ThreadPool& pool,
                        std::vector<T>& out) {
  const int w = f.width, h = f.height;
  constexpr int kOut = 5;  // r, g, b, depth, alpha
  out.resize(static_cast<std::size_t>(w) * h * kOut * 6);  // no clearing: every pixel is written
  const std::vector<Splat<T>>& splats = pack_splats(f, pool);
  const T bg[3] = {T(f.settings.background[0]), T(f.settings.background[1]),
                   T(f.settings.background[2])};
  pool.parallel_for(static_cast<std::size_t>(f.tiles_x) * f.tiles_y, [&](std::size_t tile) {
    const TileGeometry geo = tile_geometry(static_cast<int>(tile), f.tiles_x, w, h);
    // Front to back, as the forward pass: out = sum_j c_j a_j T_j, T_j = prod_{k<j} (1 - a_k),
    // so d out = sum_j T_j (dc_j a_j + c_j da_j + c_j a_j dlogT_j), dlogT_j = -sum da_k/(1-a_k).
    // Per pixel and direction k: transmittance, dlogT and the tangents of r, g, b, depth.
    alignas(64) T trans[kTilePixels], d_log_t[6][kTilePixels], d_rgb[3][6][kTilePixels],
        d_z[6][kTilePixels];
    alignas(64) int32_t last[kTilePixels];
    int64_t row_max_last[kTile] = {};
    for (int p = 0; p < kTilePixels; ++p) {
      trans[p] = 1;
      for (int k = 0; k < 6; ++k) {
        d_log_t[k][p] = d_z[k][p] = 0;
        for (int c = 0; c < 3; ++c) d_rgb[c][k][p] = 0;
      }
      const int x = p % kTile, y = p / kTile;
      last[p] = 0;
      if (x >= geo.width || y >= geo.height) continue;
      last[p] = static_cast<int32_t>(f.last_contributor[static_cast<std::size_t>(geo.y0 + y) * w + (geo.x0 + x)]);
      row_max_last[y] = std::max<int64_t>(row_max_last[y], last[p]);
    }
    int64_t max_last = 0;
    for (int y = 0; y < kTile; ++y) max_last = std::max(max_last, row_max_last[y]);
    for (int64_t s = f.tile_ranges[tile * 2]; s < max_last; ++s) {
      prefetch_splat(splats.data(), f.sorted_ids.data(), s + kPrefetchAhead, s, max_last);
      if (s + kPrefetchAhead < max_last) {  // and its screen Jacobian, 216 bytes
        const char* ahead = reinterpret_cast<const char*>(
            &screen_jvp[static_cast<std::size_t>(f.sorted_ids[s + kPrefetchAhead]) * kScreenValues * 6]);
        for (std::size_t line = 0; line < kScreenValues * 6 * sizeof(T); line += 64) __builtin_prefetch(ahead + line);
      }
      const int32_t s32 = static_cast<int32_t>(s);
      const uint32_t id = f.sorted_ids[s];
      const Splat<T> sp = splats[id];  // a copy: a reference could alias the pixel rows
      const IndexRange rows = reach_rows(sp, geo.x0, geo.y0);
      const T* jac = &screen_jvp[static_cast<std::size_t>(id) * kScreenValues * 6];
      for (int y = rows.first; y < rows.end; ++y) {
        if (s >= row_max_last[y]) continue;
        const T py = T(geo.y0 + y) + T(0.5), px0 = T(geo.x0) + T(0.5);
        const int row = y * kTile;
        // d sigma along direction k, with J_i the tangents of (mean x, mean y, conic a, b, c):
        // (a dx + b dy) J_0 + (c dy + b dx) J_1 + dx^2/2 J_2 + dx dy J_3 + dy^2/2 J_4, a
        // quadratic in dx whose coefficients are fixed along the row.
        const T dy = sp.my - py;
        T quad[6], lin[6], con[6];
        for (int k = 0; k < 6; ++k) {
          quad[k] = T(0.5) * jac[2 * 6 + k];
          lin[k] = sp.ca * jac[0 * 6 + k] + sp.cb * jac[1 * 6 + k] + dy * jac[3 * 6 + k];
          con[k] = dy * (sp.cb * jac[0 * 6 + k] + sp.cc * jac[1 * 6 + k] + T(0.5) * dy * jac[4 * 6 + k]);
        }
#pragma omp simd
        for (int x = 0; x < kTile; ++x) {
          const int p = row + x;
          const PixelEval<T> e = eval_pixel(sp, px0 + T(x), py);
          const T live = blended(s32, last[p], e);
          const T smooth = e.raw_alpha < T(io::kAlphaMax) ? live : T(0);
          const T weight = live * e.alpha * trans[p];
          const T inv = live / (1 - e.alpha);
#pragma GCC unroll 6
          for (int k = 0; k < 6; ++k) {  // unrolled: a loop here would stop the pixel loop vectorizing
            const T d_sigma = (quad[k] * e.dx + lin[k]) * e.dx + con[k];
            const T d_alpha = -smooth * e.raw_alpha * d_sigma;
            const T d_weight = live * trans[p] * (d_alpha + e.alpha * d_log_t[k][p]);
            d_rgb[0][k][p] += d_weight * sp.r + weight * jac[6 * 6 + k];
            d_rgb[1][k][p] += d_weight * sp.g + weight * jac[7 * 6 + k];
            d_rgb[2][k][p] += d_weight * sp.b + weight * jac[8 * 6 + k];
            d_z[k][p] += d_weight * sp.z + weight * jac[5 * 6 + k];
            d_log_t[k][p] -= d_alpha * inv;
          }
          trans[p] *= 1 - live * e.alpha;
        }
      }
    }
    for (int y = 0; y < geo.height; ++y) {
      for (int x = 0; x < geo.width; ++x) {
        const int p = y * kTile + x;
        const std::size_t o = static_cast<std::size_t>(geo.y0 + y) * w + (geo.x0 + x);
        T* values = &out[o * kOut * 6];
        for (int k = 0; k < 6; ++k) {
          const T d_final = trans[p] * d_log_t[k][p];  // d T_final
          for (int c = 0; c < 3; ++c) values[c * 6 + k] = d_rgb[c][k][p] + bg[c] * d_final;
          values[3 * 6 + k] = d_z[k][p];
          values[4 * 6 + k] = -d_final;
        }
      }
    }
  });
}

template void composite_pose_jvp(const ForwardResultT<float>&, const std::vector<float>&, ThreadPool&,
                                 std::vector<float>&);
template void composite_pose_jvp(const ForwardResultT<double>&, const std::vector<double>&, ThreadPool&,
                                 std::vector<double>&);

}  // namespace splat::cpu
