// The readable oracle of compositing: per tile, per pixel, per splat, one value at a time, as
// shaders/rasterize_forward.comp and rasterize_backward.comp read. It shares only the per-pixel
// maths with the vectorized passes (composite_common.h: sigma, exp, alpha); the walk over
// tiles, the cut-offs, the transmittance recovery and the gradients are written out plainly.
#include "cpu/composite_common.h"

namespace splat::cpu {
namespace {

// The splat at sorted position s of a frame, as the shaders load it.
template <typename T>
struct ScreenSplat {
  T mx, my, ca, cb, cc, opacity, color[3], depth;
};

template <typename T>
ScreenSplat<T> screen_splat(const ForwardResultT<T>& f, std::size_t id) {
  return {f.means2d[id * 2],    f.means2d[id * 2 + 1], f.conics[id * 3],
          f.conics[id * 3 + 1], f.conics[id * 3 + 2],  f.opacities[id],
          {f.colors[id * 3], f.colors[id * 3 + 1], f.colors[id * 3 + 2]},
          f.depths[id]};
}

template <typename T>
PixelEval<T> eval_at(const ScreenSplat<T>& s, T px, T py) {
  return eval_pixel(s.mx, s.my, s.ca, s.cb, s.cc, s.opacity, px, py);
}

template <typename T>
T grad_at(const std::vector<T>& v, std::size_t i) {
  return v.empty() ? T(0) : v[i];
}

}  // namespace

template <typename T>
void scalar_composite_forward(ForwardResultT<T>& f) {
  start_images(f);
  const int w = f.width, h = f.height;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t tile = static_cast<std::size_t>(y / kTile) * f.tiles_x + x / kTile;
      const T px = T(x) + T(0.5), py = T(y) + T(0.5);
      T t = 1, rgb[3] = {0, 0, 0}, z = 0;
      uint32_t last = 0;
      for (uint32_t s = f.tile_ranges[tile * 2]; s < f.tile_ranges[tile * 2 + 1]; ++s) {
        const ScreenSplat<T> sp = screen_splat(f, f.sorted_ids[s]);
        const PixelEval<T> e = eval_at(sp, px, py);
        if (e.alpha < T(io::kAlphaMin)) continue;
        const T next_t = t * (1 - e.alpha);
        if (next_t <= T(io::kTransmittanceMin)) break;  // this splat is not blended
        const T weight = e.alpha * t;
        // The colour and depth sums fuse their multiply-adds, as the vectorized pass does for
        // speed (the shader does not: they agree to rounding; alpha and transmittance exactly).
        for (int c = 0; c < 3; ++c) rgb[c] = fma_lanes(weight, sp.color[c], rgb[c]);
        z = fma_lanes(weight, sp.depth, z);
        t = next_t;
        last = s + 1;
      }
      const std::size_t o = static_cast<std::size_t>(y) * w + x;
      for (int c = 0; c < 3; ++c) f.rgb[o * 3 + c] = fma_lanes(t, T(f.settings.background[c]), rgb[c]);
      f.alpha[o] = 1 - t;
      f.depth[o] = z;
      f.depth_normalized[o] = f.alpha[o] > 0 ? z / f.alpha[o] : T(0);
      f.last_contributor[o] = last;
      f.final_transmittance[o] = t;
    }
  }
}

template <typename T>
ScreenGrads<T> scalar_composite_backward(const ForwardResultT<T>& f, const ImageGradsT<T>& d_image) {
  const int w = f.width, h = f.height;
  const std::size_t n = f.gaussians.size();
  ScreenGrads<T> g(n);
  const T bg[3] = {T(f.settings.background[0]), T(f.settings.background[1]), T(f.settings.background[2])};
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t o = static_cast<std::size_t>(y) * w + x;
      const std::size_t tile = static_cast<std::size_t>(y / kTile) * f.tiles_x + x / kTile;
      const T px = T(x) + T(0.5), py = T(y) + T(0.5);
      // Outputs: C = sum_k w_k c_k + T_final bg, D = sum_k w_k z_k, A = 1 - T_final, where
      // w_k = alpha_k T_k and T_k = prod_{j<k} (1 - alpha_j).
      const T v_rgb[3] = {grad_at(d_image.rgb, o * 3), grad_at(d_image.rgb, o * 3 + 1), grad_at(d_image.rgb, o * 3 + 2)};
      const T v_depth = grad_at(d_image.depth, o), v_alpha_out = grad_at(d_image.alpha, o);
      const T t_final = f.final_transmittance[o];
      // dL/dT_final, times T_final: what every blended splat's alpha reaches through T_final.
      const T v_final = t_final * (v_alpha_out - (bg[0] * v_rgb[0] + bg[1] * v_rgb[1] + bg[2] * v_rgb[2]));
      T t = t_final;                     // transmittance behind the current splat
      T behind[3] = {0, 0, 0}, behind_z = 0;  // colour and depth blended behind it
      const uint32_t begin = f.tile_ranges[tile * 2];
      for (uint32_t s = f.last_contributor[o]; s-- > begin;) {
        const std::size_t id = f.sorted_ids[s];
        const ScreenSplat<T> sp = screen_splat(f, id);
        const PixelEval<T> e = eval_at(sp, px, py);
        if (e.alpha < T(io::kAlphaMin)) continue;  // the forward pass skipped it
        const T inv = 1 / (1 - e.alpha);
        t *= inv;  // in front of this splat
        const T weight = e.alpha * t;
        // dL/dalpha_k = sum over outputs of T_k (value_k - behind_k / (1 - alpha_k)) dL/dout,
        // and -T_final / (1 - alpha_k) dL/dT_final.
        T v_alpha = (sp.depth * t - behind_z * inv) * v_depth + v_final * inv;
        for (int c = 0; c < 3; ++c) {
          v_alpha += (sp.color[c] * t - behind[c] * inv) * v_rgb[c];
          g.colors[id * 3 + c] += weight * v_rgb[c];
          behind[c] += weight * sp.color[c];
        }
        g.depths[id] += weight * v_depth;
        behind_z += weight * sp.depth;
        // alpha = min(kAlphaMax, opacity exp(-sigma)): no gradient where capped.
        if (!(e.raw_alpha < T(io::kAlphaMax))) continue;
        g.opacities[id] += e.gauss * v_alpha;
        const T v_sigma = -sp.opacity * e.gauss * v_alpha;
        // sigma = a dx^2 / 2 + b dx dy + c dy^2 / 2, (dx, dy) = mean - pixel.
        g.conics[id * 3] += T(0.5) * e.dx * e.dx * v_sigma;
        g.conics[id * 3 + 1] += e.dx * e.dy * v_sigma;
        g.conics[id * 3 + 2] += T(0.5) * e.dy * e.dy * v_sigma;
        g.means2d[id * 2] += (sp.ca * e.dx + sp.cb * e.dy) * v_sigma;
        g.means2d[id * 2 + 1] += (sp.cb * e.dx + sp.cc * e.dy) * v_sigma;
      }
    }
  }
  return g;
}

template void scalar_composite_forward(ForwardResultT<float>&);
template void scalar_composite_forward(ForwardResultT<double>&);
template ScreenGrads<float> scalar_composite_backward(const ForwardResultT<float>&, const ImageGradsT<float>&);
template ScreenGrads<double> scalar_composite_backward(const ForwardResultT<double>&, const ImageGradsT<double>&);

}  // namespace splat::cpu
