// Front-to-back alpha compositing per 16x16 tile, and its backward pass. Within a tile the loop
// runs splat by splat over the tile's pixels, so the pixel loop vectorizes.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

#include "cpu/stages.h"
#include "shader_io.h"

namespace splat::cpu {
namespace {

// Gradient slots per intersection in the backward pass (the order of shader_io.h).
enum Slot { kMx, kMy, kCa, kCb, kCc, kOpacity, kR, kG, kB, kZ, kSlots };
static_assert(kSlots == io::kGradSlots && kOpacity == io::kSlotOpacity && kZ == io::kSlotDepth);

constexpr int kTile = static_cast<int>(io::kTileSize);
constexpr int kTilePixels = kTile * kTile;

// One splat's screen parameters, gathered so the pixel loop reads registers only.
template <typename T>
struct Splat {
  T mx, my;       // 2D mean, pixels
  T ca, cb, cc;   // conic
  T opacity;
  T r, g, b, z;   // colour and camera depth
};

template <typename T>
Splat<T> load_splat(const ForwardResultT<T>& f, uint32_t id) {
  return {f.means2d[id * 2],      f.means2d[id * 2 + 1], f.conics[id * 3], f.conics[id * 3 + 1],
          f.conics[id * 3 + 2],   f.opacities[id],       f.colors[id * 3], f.colors[id * 3 + 1],
          f.colors[id * 3 + 2],   f.depths[id]};
}

// Tile-local pixel rectangle [x0, x1) x [y0, y1) worth evaluating for a splat: its extent box
// grown by one pixel. Outside the extent box alpha < kAlphaMin analytically (the extent is
// where opacity * exp(-sigma) reaches kAlphaMin), so this equals evaluating the whole tile;
// the one-pixel margin keeps rounding at the box edge from changing any pixel. The loops below
// cut rows only and evaluate whole 16-pixel rows, one vector each.
struct PixelRect {
  int x0, y0, x1, y1;
  bool empty() const { return x0 >= x1 || y0 >= y1; }
};

template <typename T>
PixelRect splat_rect(const ForwardResultT<T>& f, uint32_t id, int tile_x0, int tile_y0) {
  const T mx = f.means2d[id * 2] - T(tile_x0), my = f.means2d[id * 2 + 1] - T(tile_y0);
  const T rx = T(f.radii[id * 2] + 1), ry = T(f.radii[id * 2 + 1] + 1);
  // Pixel x (centre x + 0.5) is inside when mx - rx <= x + 0.5 <= mx + rx.
  auto lo = [](T v) { return static_cast<int>(std::clamp(std::ceil(v - T(0.5)), T(0), T(kTile))); };
  auto hi = [](T v) {
    return static_cast<int>(std::clamp(std::floor(v - T(0.5)) + 1, T(0), T(kTile)));
  };
  return {lo(mx - rx), lo(my - ry), hi(mx + rx), hi(my + ry)};
}

// Whether any pixel centre px in [px_first, px_last] of the row at py can reach alpha >= kAlphaMin.
// Along a row sigma is a parabola in dx = mx - px: 0.5 a (dx - dx0)^2 + 0.5 dy^2 (c - b^2/a)
// with dx0 = -b dy / a, so the test is exact; `limit` is ln(opacity / kAlphaMin) widened by
// kRowCullSlack, so rounding in the pixel loop can never make a skipped row count.
inline constexpr double kRowCullSlack = 0.05;  // keeps rows down to 0.95 * kAlphaMin
template <typename T>
bool row_reaches(const Splat<T>& sp, T limit, T py, T px_first, T px_last) {
  const T dy = sp.my - py;
  const T sigma_min = T(0.5) * dy * dy * (sp.cc - sp.cb * sp.cb / sp.ca);
  if (sigma_min > limit) return false;
  const T centre = sp.mx + sp.cb * dy / sp.ca;  // px where sigma is smallest on this row
  const T half = std::sqrt(2 * (limit - sigma_min) / sp.ca);
  return centre + half >= px_first && centre - half <= px_last;
}

template <typename T>
T row_cull_limit(const Splat<T>& sp) {
  return std::log(sp.opacity / T(io::kAlphaMin)) + T(kRowCullSlack);
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
// plain arithmetic so the pixel loop vectorizes (libm's expf does not without -ffast-math).
// Double: std::exp, for gradient checks.
inline float exp_nonpositive(float x) {
  x = std::max(x, -87.f);  // below this the result is under 2^-126 and would flush anyway
  const float n = std::floor(x * 1.44269504088896341f + 0.5f);
  const float r = x - n * 0.693359375f + n * 2.12194440e-4f;  // x - n ln2, in two parts
  float p = 1.9875691500e-4f;
  p = p * r + 1.3981999507e-3f;
  p = p * r + 8.3334519073e-3f;
  p = p * r + 4.1665795894e-2f;
  p = p * r + 1.6666665459e-1f;
  p = p * r + 5.0000001201e-1f;
  p = p * r * r + r + 1.f;
  return p * std::bit_cast<float>((static_cast<int32_t>(n) + 127) << 23);
}
inline double exp_nonpositive(double x) { return std::exp(x); }

template <typename T>
inline PixelEval<T> eval_pixel(const Splat<T>& s, T px, T py) {
  PixelEval<T> e;
  e.dx = s.mx - px;
  e.dy = s.my - py;
  e.sigma = T(0.5) * (s.ca * e.dx * e.dx + s.cc * e.dy * e.dy) + s.cb * e.dx * e.dy;
  e.gauss = exp_nonpositive(-std::max(e.sigma, T(0)));
  e.raw_alpha = e.sigma >= 0 ? s.opacity * e.gauss : T(0);
  e.alpha = std::min(T(io::kAlphaMax), e.raw_alpha);
  return e;
}

// 1 where the forward pass blended sorted splat s into a pixel whose contributors end at
// `last`, else 0 (a float select, so the pixel loops stay vectorized).
template <typename T>
inline T blended(int64_t s, int32_t last, const PixelEval<T>& e) {
  const T alpha_here = s < last ? e.alpha : T(0);
  return alpha_here >= T(io::kAlphaMin) ? T(1) : T(0);
}

struct TileGeometry {
  int x0, y0;          // first pixel of the tile
  int width, height;   // pixels of the tile inside the image
};

TileGeometry tile_geometry(int tile, int tiles_x, int image_w, int image_h) {
  const int x0 = (tile % tiles_x) * kTile, y0 = (tile / tiles_x) * kTile;
  return {x0, y0, std::min(kTile, image_w - x0), std::min(kTile, image_h - y0)};
}

}  // namespace

template <typename T>
void composite_forward(ForwardResultT<T>& f, ThreadPool& pool) {
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

  pool.parallel_for(static_cast<std::size_t>(f.tiles_x) * f.tiles_y, [&](std::size_t tile) {
    const TileGeometry geo = tile_geometry(static_cast<int>(tile), f.tiles_x, w, h);
    alignas(64) T trans[kTilePixels], acc_r[kTilePixels], acc_g[kTilePixels],
        acc_b[kTilePixels], acc_z[kTilePixels], done[kTilePixels];
    alignas(64) int32_t last[kTilePixels];
    int row_live[kTile];  // pixels of each row still compositing
    for (int p = 0; p < kTilePixels; ++p) {
      trans[p] = 1;
      acc_r[p] = acc_g[p] = acc_b[p] = acc_z[p] = 0;
      last[p] = 0;
      // Pixels past the image edge start finished so they never hold the tile open.
      done[p] = (p % kTile) >= geo.width || (p / kTile) >= geo.height;
    }
    for (int y = 0; y < kTile; ++y) row_live[y] = y < geo.height ? geo.width : 0;
    int remaining = geo.width * geo.height;
    const uint32_t begin = f.tile_ranges[tile * 2], end = f.tile_ranges[tile * 2 + 1];
    for (uint32_t s = begin; s < end && remaining > 0; ++s) {
      const uint32_t id = f.sorted_ids[s];
      const PixelRect rect = splat_rect(f, id, geo.x0, geo.y0);
      if (rect.empty()) continue;
      const Splat<T> sp = load_splat(f, id);
      const T limit = row_cull_limit(sp);
      const int32_t next_last = static_cast<int32_t>(s + 1);
      for (int y = rect.y0; y < rect.y1; ++y) {
        if (row_live[y] == 0) continue;
        const T py = T(geo.y0 + y) + T(0.5), px0 = T(geo.x0) + T(0.5);
        if (!row_reaches(sp, limit, py, px0, px0 + T(kTile - 1))) continue;
        T* row_trans = trans + y * kTile;
        T* row_done = done + y * kTile;
        T* row_r = acc_r + y * kTile;
        T* row_g = acc_g + y * kTile;
        T* row_b = acc_b + y * kTile;
        T* row_z = acc_z + y * kTile;
        int32_t* row_last = last + y * kTile;
#pragma omp simd
        for (int x = 0; x < kTile; ++x) {
          const PixelEval<T> e = eval_pixel(sp, px0 + T(x), py);
          const T t = row_trans[x];
          const T next_t = t * (1 - e.alpha);
          // 1 where the splat blends into a still-compositing pixel; 0 otherwise.
          const T live = e.alpha >= T(io::kAlphaMin) ? 1 - row_done[x] : T(0);
          const T stop = next_t <= T(io::kTransmittanceMin) ? live : T(0);
          const T add = live - stop;
          const T weight = add * e.alpha * t;
          row_r[x] += weight * sp.r;
          row_g[x] += weight * sp.g;
          row_b[x] += weight * sp.b;
          row_z[x] += weight * sp.z;
          row_trans[x] = add > 0 ? next_t : t;
          row_last[x] = add > 0 ? next_last : row_last[x];
          row_done[x] += stop;
        }
        int live = 0;
        for (int x = 0; x < kTile; ++x) live += row_done[x] == 0;
        const int finished = row_live[y] - live;
        row_live[y] = live;
        remaining -= finished;
      }
    }
    for (int y = 0; y < geo.height; ++y) {
      for (int x = 0; x < geo.width; ++x) {
        const int p = y * kTile + x;
        const std::size_t o = static_cast<std::size_t>(geo.y0 + y) * w + (geo.x0 + x);
        f.rgb[o * 3] = acc_r[p] + trans[p] * bg[0];
        f.rgb[o * 3 + 1] = acc_g[p] + trans[p] * bg[1];
        f.rgb[o * 3 + 2] = acc_b[p] + trans[p] * bg[2];
        f.alpha[o] = 1 - trans[p];
        f.depth[o] = acc_z[p];
        f.depth_normalized[o] = f.alpha[o] > 0 ? acc_z[p] / f.alpha[o] : T(0);
        f.last_contributor[o] = static_cast<uint32_t>(last[p]);
        f.final_transmittance[o] = trans[p];
      }
    }
  });
}

template <typename T>
ScreenGrads<T> composite_backward(const ForwardResultT<T>& f, const ImageGradsT<T>& d_image,
                                  ThreadPool& pool, std::vector<T>& scratch) {
  const int w = f.width, h = f.height;
  const std::size_t n = f.gaussians.size();
  // Gradients per intersection (sorted position): every intersection belongs to one tile, so
  // tiles write disjoint slots; the per-Gaussian sum below runs in a fixed order.
  // Every slot of every tile is written below, so the reused buffer needs no clearing.
  std::vector<T>& isect = scratch;
  if (isect.size() < f.sorted_ids.size() * kSlots) isect.resize(f.sorted_ids.size() * kSlots);
  const T bg[3] = {T(f.settings.background[0]), T(f.settings.background[1]),
                   T(f.settings.background[2])};
  auto grad_at = [](const std::vector<T>& v, std::size_t i) { return v.empty() ? T(0) : v[i]; };

  pool.parallel_for(static_cast<std::size_t>(f.tiles_x) * f.tiles_y, [&](std::size_t tile) {
    const TileGeometry geo = tile_geometry(static_cast<int>(tile), f.tiles_x, w, h);
    // Per pixel: transmittance walking back to front, colour/depth accumulated behind the
    // current splat, upstream gradients and the alpha/background term T_final (dA - bg.dC).
    alignas(64) T trans[kTilePixels], behind_r[kTilePixels], behind_g[kTilePixels],
        behind_b[kTilePixels], behind_z[kTilePixels], v_r[kTilePixels], v_g[kTilePixels],
        v_b[kTilePixels], v_z[kTilePixels], v_final[kTilePixels];
    alignas(64) int32_t last[kTilePixels];
    int32_t max_last = 0;
    int64_t row_max_last[kTile] = {};  // per row: one past the last splat any pixel used
    for (int p = 0; p < kTilePixels; ++p) {
      const int x = p % kTile, y = p / kTile;
      trans[p] = 1;
      behind_r[p] = behind_g[p] = behind_b[p] = behind_z[p] = 0;
      v_r[p] = v_g[p] = v_b[p] = v_z[p] = v_final[p] = 0;
      last[p] = 0;
      if (x >= geo.width || y >= geo.height) continue;
      const std::size_t o = static_cast<std::size_t>(geo.y0 + y) * w + (geo.x0 + x);
      trans[p] = f.final_transmittance[o];
      v_r[p] = grad_at(d_image.rgb, o * 3);
      v_g[p] = grad_at(d_image.rgb, o * 3 + 1);
      v_b[p] = grad_at(d_image.rgb, o * 3 + 2);
      v_z[p] = grad_at(d_image.depth, o);
      // rgb += T_final bg and alpha = 1 - T_final; dT_final/dalpha_j = -T_final / (1 - alpha_j).
      v_final[p] = trans[p] * (grad_at(d_image.alpha, o) -
                               (bg[0] * v_r[p] + bg[1] * v_g[p] + bg[2] * v_b[p]));
      last[p] = static_cast<int32_t>(f.last_contributor[o]);
      max_last = std::max(max_last, last[p]);
      row_max_last[y] = std::max<int64_t>(row_max_last[y], last[p]);
    }
    const uint32_t begin = f.tile_ranges[tile * 2];
    for (int64_t s = int64_t(max_last) - 1; s >= int64_t(begin); --s) {
      const uint32_t id = f.sorted_ids[s];
      const PixelRect rect = splat_rect(f, id, geo.x0, geo.y0);
      if (rect.empty()) continue;
      const Splat<T> sp = load_splat(f, id);
      const T limit = row_cull_limit(sp);
      // Per-lane partial sums over the rows, reduced once per splat (in a fixed order).
      alignas(64) T lanes[kSlots][kTile] = {};
      for (int y = rect.y0; y < rect.y1; ++y) {
        if (s >= row_max_last[y]) continue;  // no pixel of this row composited this splat
        const T py = T(geo.y0 + y) + T(0.5), px0 = T(geo.x0) + T(0.5);
        if (!row_reaches(sp, limit, py, px0, px0 + T(kTile - 1))) continue;
        const int row = y * kTile;
#pragma omp simd
        for (int x = 0; x < kTile; ++x) {
          const int p = row + x;
          const PixelEval<T> e = eval_pixel(sp, px0 + T(x), py);
          const T live = blended(s, last[p], e);
          const T inv = live / (1 - e.alpha);
          const T t = live > 0 ? trans[p] * inv : trans[p];  // transmittance in front of it
          const T weight = live * e.alpha * t;
          // dL/dalpha: own contribution minus what it hides behind, plus the T_final terms.
          const T v_alpha = (sp.r * t - behind_r[p] * inv) * v_r[p] +
                            (sp.g * t - behind_g[p] * inv) * v_g[p] +
                            (sp.b * t - behind_b[p] * inv) * v_b[p] +
                            (sp.z * t - behind_z[p] * inv) * v_z[p] + v_final[p] * inv;
          lanes[kR][x] += weight * v_r[p];
          lanes[kG][x] += weight * v_g[p];
          lanes[kB][x] += weight * v_b[p];
          lanes[kZ][x] += weight * v_z[p];
          behind_r[p] += weight * sp.r;
          behind_g[p] += weight * sp.g;
          behind_b[p] += weight * sp.b;
          behind_z[p] += weight * sp.z;
          trans[p] = t;
          // alpha = min(kAlphaMax, opacity * exp(-sigma)): no gradient where capped.
          const T smooth = e.raw_alpha < T(io::kAlphaMax) ? live : T(0);
          const T v_sigma = -smooth * sp.opacity * e.gauss * v_alpha;
          lanes[kOpacity][x] += smooth * e.gauss * v_alpha;
          lanes[kCa][x] += T(0.5) * e.dx * e.dx * v_sigma;
          lanes[kCc][x] += T(0.5) * e.dy * e.dy * v_sigma;
          lanes[kCb][x] += e.dx * e.dy * v_sigma;
          lanes[kMx][x] += (sp.ca * e.dx + sp.cb * e.dy) * v_sigma;
          lanes[kMy][x] += (sp.cc * e.dy + sp.cb * e.dx) * v_sigma;
        }
      }
      T* out = &isect[static_cast<std::size_t>(s) * kSlots];
      for (int k = 0; k < kSlots; ++k) {
        T sum = 0;
        for (int x = 0; x < kTile; ++x) sum += lanes[k][x];
        out[k] = sum;
      }
    }
    // Splats behind every pixel's last contributor got no gradient.
    std::fill(isect.begin() + std::max<int64_t>(max_last, begin) * kSlots,
              isect.begin() + int64_t(f.tile_ranges[tile * 2 + 1]) * kSlots, T(0));
  });

  ScreenGrads<T> g;
  g.means2d.assign(n * 2, 0);
  g.conics.assign(n * 3, 0);
  g.opacities.assign(n, 0);
  g.colors.assign(n * 3, 0);
  g.depths.assign(n, 0);
  for (std::size_t s = 0; s < f.sorted_ids.size(); ++s) {
    const std::size_t id = f.sorted_ids[s];
    const T* in = &isect[s * kSlots];
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
std::vector<T> composite_pose_jvp(const ForwardResultT<T>& f, const std::vector<T>& screen_jvp,
                                  ThreadPool& pool) {
  const int w = f.width, h = f.height;
  constexpr int kOut = 5;  // r, g, b, depth, alpha
  std::vector<T> out(static_cast<std::size_t>(w) * h * kOut * 6, T(0));
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
      const uint32_t id = f.sorted_ids[s];
      const PixelRect rect = splat_rect(f, id, geo.x0, geo.y0);
      if (rect.empty()) continue;
      const Splat<T> sp = load_splat(f, id);
      const T limit = row_cull_limit(sp);
      const T* jac = &screen_jvp[static_cast<std::size_t>(id) * kScreenValues * 6];
      for (int y = rect.y0; y < rect.y1; ++y) {
        if (s >= row_max_last[y]) continue;
        const T py = T(geo.y0 + y) + T(0.5), px0 = T(geo.x0) + T(0.5);
        if (!row_reaches(sp, limit, py, px0, px0 + T(kTile - 1))) continue;
        const int row = y * kTile;
#pragma omp simd
        for (int x = 0; x < kTile; ++x) {
          const int p = row + x;
          const PixelEval<T> e = eval_pixel(sp, px0 + T(x), py);
          const T live = blended(s, last[p], e);
          const T smooth = e.raw_alpha < T(io::kAlphaMax) ? live : T(0);
          const T weight = live * e.alpha * trans[p];
          const T inv = live / (1 - e.alpha);
          // dsigma/d(mean x, mean y, conic a, b, c) at this pixel.
          const T ds[5] = {sp.ca * e.dx + sp.cb * e.dy, sp.cc * e.dy + sp.cb * e.dx, T(0.5) * e.dx * e.dx,
                           e.dx * e.dy, T(0.5) * e.dy * e.dy};
#pragma GCC unroll 6
          for (int k = 0; k < 6; ++k) {  // unrolled: a loop here would stop the pixel loop vectorizing
            const T d_sigma = ds[0] * jac[0 * 6 + k] + ds[1] * jac[1 * 6 + k] + ds[2] * jac[2 * 6 + k] +
                              ds[3] * jac[3 * 6 + k] + ds[4] * jac[4 * 6 + k];
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
  return out;
}

template std::vector<float> composite_pose_jvp(const ForwardResultT<float>&, const std::vector<float>&,
                                               ThreadPool&);
template std::vector<double> composite_pose_jvp(const ForwardResultT<double>&,
                                                const std::vector<double>&, ThreadPool&);

}  // namespace splat::cpu
