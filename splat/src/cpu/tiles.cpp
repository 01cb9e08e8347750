#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>

#include "cpu/stages.h"
#include "shader_io.h"
#include "splat/error.h"

namespace splat::cpu {
namespace {

struct TileBox {
  int x0, y0, x1, y1;  // tiles [x0, x1) x [y0, y1)
  int count() const { return (x1 - x0) * (y1 - y0); }
};

// Tiles touched by a splat's per-axis extent box, clamped to the grid (gsplat's isect_tiles).
template <typename T>
TileBox tile_box(const ForwardResultT<T>& f, std::size_t i) {
  const int rx = f.radii[i * 2], ry = f.radii[i * 2 + 1];
  if (rx <= 0 && ry <= 0) return {0, 0, 0, 0};
  const T tile = T(io::kTileSize);
  const T mx = f.means2d[i * 2] / tile, my = f.means2d[i * 2 + 1] / tile;
  const T ex = T(rx) / tile, ey = T(ry) / tile;
  auto clamp_to = [](T v, int hi) { return std::clamp(static_cast<int>(v), 0, hi); };
  // Clamp in floating point first so huge values cannot overflow the int conversion.
  auto grid = [&](T v, int hi) { return clamp_to(std::clamp(v, T(0), T(hi)), hi); };
  return {grid(std::floor(mx - ex), f.tiles_x), grid(std::floor(my - ey), f.tiles_y),
          grid(std::ceil(mx + ex), f.tiles_x), grid(std::ceil(my + ey), f.tiles_y)};
}

// Visible splat ids in front-to-back order, ties by index (as a stable radix sort of gsplat's
// keys orders them): a stable LSD radix sort, 3 passes of 11 bits, of the depths' float bits
// (positive, so the bits order like the values) over ids taken in increasing order.
template <typename T>
std::vector<uint32_t> depth_order(const ForwardResultT<T>& f) {
  std::vector<uint32_t> ids, keys;
  ids.reserve(f.stats.visible);
  keys.reserve(f.stats.visible);
  for (std::size_t i = 0; i < f.gaussians.size(); ++i) {
    if (f.radii[i * 2] > 0 || f.radii[i * 2 + 1] > 0) {
      ids.push_back(static_cast<uint32_t>(i));
      keys.push_back(std::bit_cast<uint32_t>(static_cast<float>(f.depths[i])));
    }
  }
  std::vector<uint32_t> ids_tmp(ids.size()), keys_tmp(keys.size());
  constexpr int kBits = 11, kBuckets = 1 << kBits;
  for (int shift = 0; shift < 32; shift += kBits) {
    std::vector<uint32_t> start(kBuckets + 1, 0);
    for (uint32_t k : keys) ++start[((k >> shift) & (kBuckets - 1)) + 1];
    for (int b = 0; b < kBuckets; ++b) start[b + 1] += start[b];
    for (std::size_t j = 0; j < keys.size(); ++j) {
      const uint32_t slot = start[(keys[j] >> shift) & (kBuckets - 1)]++;
      keys_tmp[slot] = keys[j];
      ids_tmp[slot] = ids[j];
    }
    keys.swap(keys_tmp);
    ids.swap(ids_tmp);
  }
  return ids;
}

}  // namespace

template <typename T>
void bin_and_sort(ForwardResultT<T>& f, ThreadPool& pool) {
  f.tiles_x = static_cast<int>((f.camera.width + io::kTileSize - 1) / io::kTileSize);
  f.tiles_y = static_cast<int>((f.camera.height + io::kTileSize - 1) / io::kTileSize);
  const std::size_t tiles = static_cast<std::size_t>(f.tiles_x) * f.tiles_y;

  // 1. Visible splats in front-to-back order, once: sorting N splats is far cheaper than
  //    sorting every tile's list, and a stable scatter below keeps each tile in this order.
  const std::vector<uint32_t> order = depth_order(f);
  std::vector<TileBox> boxes(order.size());

  // 2. Count intersections per tile in fixed chunks of that order (no atomics; the chunking
  //    does not depend on the thread count).
  constexpr std::size_t kChunk = 4096;
  const std::size_t chunks = (order.size() + kChunk - 1) / kChunk;
  std::vector<uint32_t> chunk_counts(chunks * tiles, 0);
  auto chunk_splats = [&](std::size_t c, auto&& visit) {
    for (std::size_t k = c * kChunk; k < std::min(order.size(), (c + 1) * kChunk); ++k) {
      const TileBox& b = boxes[k];
      for (int ty = b.y0; ty < b.y1; ++ty)
        for (int tx = b.x0; tx < b.x1; ++tx) visit(static_cast<std::size_t>(ty * f.tiles_x + tx), order[k]);
    }
  };
  pool.parallel_for(chunks, [&](std::size_t c) {
    for (std::size_t k = c * kChunk; k < std::min(order.size(), (c + 1) * kChunk); ++k) {
      boxes[k] = tile_box(f, order[k]);
    }
    uint32_t* counts = &chunk_counts[c * tiles];
    chunk_splats(c, [&](std::size_t tile, uint32_t) { ++counts[tile]; });
  });
  // 3. Exclusive prefix over (tile, chunk): where each chunk writes inside each tile's range.
  f.tile_ranges.assign(tiles * 2, 0);
  uint64_t offset = 0;
  for (std::size_t t = 0; t < tiles; ++t) {
    f.tile_ranges[t * 2] = static_cast<uint32_t>(offset);
    for (std::size_t c = 0; c < chunks; ++c) {
      const uint32_t count = chunk_counts[c * tiles + t];
      chunk_counts[c * tiles + t] = static_cast<uint32_t>(offset);
      offset += count;
    }
    // Sorted positions are int32 in compositing (last contributors, vector compares).
    if (offset > static_cast<uint64_t>(INT32_MAX)) {
      throw Error("rasterize: more than 2^31 (splat, tile) intersections; render at a lower resolution or with fewer Gaussians");
    }
    f.tile_ranges[t * 2 + 1] = static_cast<uint32_t>(offset);
  }
  f.stats.intersections = offset;
  // 4. Scatter in depth order: each tile's list comes out sorted by (depth, index).
  f.sorted_ids.resize(offset);
  pool.parallel_for(chunks, [&](std::size_t c) {
    uint32_t* slots = &chunk_counts[c * tiles];
    chunk_splats(c, [&](std::size_t tile, uint32_t id) { f.sorted_ids[slots[tile]++] = id; });
  });
}

template void bin_and_sort(ForwardResultT<float>&, ThreadPool&);
template void bin_and_sort(ForwardResultT<double>&, ThreadPool&);

}  // namespace splat::cpu
