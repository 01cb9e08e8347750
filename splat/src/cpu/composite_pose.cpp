// Forward-mode derivative of compositing with respect to the camera pose: the per-pixel
// Jacobian of colour, depth and alpha that Gauss-Newton tracking uses.
#include <algorithm>
#include <bit>
#include <cstdint>
#include <limits>

#include "cpu/composite_common.h"

namespace splat::cpu {

// kViewDependent: whether colours change with the viewpoint (SH degree > 0). Where they do not,
// their tangents are zero and the pixel loop skips 18 of its 42 multiply-adds per direction
// pair.
template <bool kViewDependent, typename T>
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
            const T d_sigma = fma_lanes(fma_lanes(quad[k], e.dx, lin[k]), e.dx, con[k]);
            const T d_alpha = -smooth * e.raw_alpha * d_sigma;
            const T d_weight = live * trans[p] * (d_alpha + e.alpha * d_log_t[k][p]);
            d_rgb[0][k][p] = fma_lanes(d_weight, sp.r, d_rgb[0][k][p]);
            d_rgb[1][k][p] = fma_lanes(d_weight, sp.g, d_rgb[1][k][p]);
            d_rgb[2][k][p] = fma_lanes(d_weight, sp.b, d_rgb[2][k][p]);
            if constexpr (kViewDependent) {
              d_rgb[0][k][p] = fma_lanes(weight, jac[6 * 6 + k], d_rgb[0][k][p]);
              d_rgb[1][k][p] = fma_lanes(weight, jac[7 * 6 + k], d_rgb[1][k][p]);
              d_rgb[2][k][p] = fma_lanes(weight, jac[8 * 6 + k], d_rgb[2][k][p]);
            }
            d_z[k][p] = fma_lanes(d_weight, sp.z, fma_lanes(weight, jac[5 * 6 + k], d_z[k][p]));
            d_log_t[k][p] = fma_lanes(-d_alpha, inv, d_log_t[k][p]);
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

template <typename T>
void composite_pose_jvp(const ForwardResultT<T>& f, const std::vector<T>& screen_jvp, ThreadPool& pool,
                        std::vector<T>& out) {
  if (f.gaussians.sh_degree > 0) {
    composite_pose_jvp<true>(f, screen_jvp, pool, out);
  } else {
    composite_pose_jvp<false>(f, screen_jvp, pool, out);
  }
}

template void composite_pose_jvp(const ForwardResultT<float>&, const std::vector<float>&, ThreadPool&,
                                 std::vector<float>&);
template void composite_pose_jvp(const ForwardResultT<double>&, const std::vector<double>&, ThreadPool&,
                                 std::vector<double>&);

}  // namespace splat::cpu
