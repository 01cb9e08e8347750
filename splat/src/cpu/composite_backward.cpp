// Backward of compositing: per tile, back to front, gradients of each splat's screen quantities
// per intersection, then summed per Gaussian in a fixed order.
#include <algorithm>
#include <bit>
#include <cstdint>
#include <limits>

#include "cpu/composite_common.h"

namespace splat::cpu {

// During the row walk the slots of the mean and conic hold moments of v_sigma: sums of
// v_sigma times dx, dy, dx^2, dx dy and dy^2, where (dx, dy) is the mean minus the pixel.
enum MomentSlot { kMomentX = kMx, kMomentY = kMy, kMomentXX = kCa, kMomentXY = kCb, kMomentYY = kCc };

// The moments to dL/d(mean) and dL/d(conic), from sigma = (a dx^2 + 2 b dx dy + c dy^2) / 2.
template <typename T>
void moments_to_gradients(const Splat<T>& sp, T* g) {
  const T x = g[kMomentX], y = g[kMomentY], xx = g[kMomentXX], xy = g[kMomentXY], yy = g[kMomentYY];
  g[kMx] = sp.ca * x + sp.cb * y;
  g[kMy] = sp.cc * y + sp.cb * x;
  g[kCa] = T(0.5) * xx;
  g[kCb] = xy;
  g[kCc] = T(0.5) * yy;
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
  using Mask = LaneMask<T>;
  using M = typename Mask::M;

  const TileLanes<T> lanes;

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
    const V px = lanes.centre + T(geo.x0), py = lanes.centre + T(geo.y0);
    // Back to front in chunks, as the forward pass goes front to back: chunk splat k (the k-th
    // from the back) reaches the rows of bit k, and its gradients add up per lane over the rows.
    Chunk<T> chunk;
    const Splat<T>* kept[kChunkSplats];  // the chunk's splats that reach a row, back to front
    int32_t chunk_pos[kChunkSplats];
    SigmaTerms<T> terms[kChunkSplats];
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
        const RowInt reached = lanes.index_int >= chunk.first[j] && lanes.index_int < chunk.end[j] && s < max_last;
        row_bits |= reached ? int32_t(1u << count) : 0;
        count += any_lane(reached);
      }
      for (int k = 0; k < count; ++k) {
        terms[k] = SigmaTerms<T>(*kept[k], px, py);
        for (int slot_k = 0; slot_k < kSlots; ++slot_k) chunk_grads[k][slot_k] = V{};
      }
      for (int y = 0; y < kTile; ++y) {
        uint32_t bits = static_cast<uint32_t>(row_bits[y]);
        if (bits == 0) continue;
        V t_row = trans[y], br = behind_r[y], bgr = behind_g[y], bb = behind_b[y], bz = behind_z[y];
        const V vr = v_r[y], vg = v_g[y], vb = v_b[y], vz = v_z[y], vf = v_final[y];
        const RowMask l = last[y];
        for (; bits != 0; bits &= bits - 1) {
          const int k = std::countr_zero(bits);
          const Splat<T>& sp = *kept[k];
          PixelEval<V> e;
          e.sigma = terms[k].sigma(y);
          eval_alpha(sp, e);
          // Where the forward pass blended this splat: in front of the pixel's last one.
          const M live = Mask::ge(e.alpha, T(io::kAlphaMin), Mask::int_less(chunk_pos[k], l));
          const V inv = Mask::select(live, T(1) / (1 - e.alpha), V{});
          const V t = Mask::select(live, t_row * inv, t_row);  // transmittance in front of it
          const V weight = Mask::select(live, e.alpha * t, V{});
          // dL/dalpha: own contribution minus what it hides behind, plus the T_final terms.
          const V v_alpha = (sp.r * t - br * inv) * vr + (sp.g * t - bgr * inv) * vg +
                            (sp.b * t - bb * inv) * vb + (sp.z * t - bz * inv) * vz + vf * inv;
          V* grads = chunk_grads[k];
          grads[kR] = fma_lanes(weight, vr, grads[kR]);
          grads[kG] = fma_lanes(weight, vg, grads[kG]);
          grads[kB] = fma_lanes(weight, vb, grads[kB]);
          grads[kZ] = fma_lanes(weight, vz, grads[kZ]);
          br = fma_lanes(weight, sp.r, br);
          bgr = fma_lanes(weight, sp.g, bgr);
          bb = fma_lanes(weight, sp.b, bb);
          bz = fma_lanes(weight, sp.z, bz);
          t_row = t;
          // alpha = min(kAlphaMax, opacity * exp(-sigma)): no gradient where capped.
          const M smooth = Mask::lt(e.raw_alpha, T(io::kAlphaMax), live);
          const V v_sigma = Mask::select(smooth, -sp.opacity * e.gauss * v_alpha, V{});
          grads[kOpacity] += Mask::select(smooth, e.gauss * v_alpha, V{});
          // The conic and mean gradients are sums of v_sigma times dx^2 / 2, dx dy, dy^2 / 2,
          // a dx + b dy and c dy + b dx; dy is one value per row, so the lanes gather the
          // moments of dx and dy and the conic combines them once per chunk (below).
          const T dy = sp.my - py[y];  // mean minus pixel, as terms' dx
          const V dx_v = terms[k].dx * v_sigma;
          grads[kMomentX] += dx_v;
          grads[kMomentXX] = fma_lanes(terms[k].dx, dx_v, grads[kMomentXX]);
          grads[kMomentXY] = fma_lanes(dy, dx_v, grads[kMomentXY]);
          grads[kMomentY] = fma_lanes(dy, v_sigma, grads[kMomentY]);
          grads[kMomentYY] = fma_lanes(dy * dy, v_sigma, grads[kMomentYY]);
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
        moments_to_gradients(*kept[k], out);
      }
    }
  });

  ScreenGrads<T> g(n);
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

template ScreenGrads<float> composite_backward(const ForwardResultT<float>&,
                                               const ImageGradsT<float>&, ThreadPool&,
                                               std::vector<float>&);
template ScreenGrads<double> composite_backward(const ForwardResultT<double>&,
                                                const ImageGradsT<double>&, ThreadPool&,
                                                std::vector<double>&);

}  // namespace splat::cpu
