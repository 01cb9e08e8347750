#include "splat/losses.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "splat/error.h"
#include "splat/thread_pool.h"

namespace splat {
namespace {

template <typename T>
void check_sizes(const char* name, std::size_t pred, std::size_t target, std::size_t grad,
                 std::size_t mask, std::size_t pixels) {
  if (target != pred || grad != pred || (mask != 0 && mask != pixels)) {
    throw Error(std::string(name) + ": sizes differ: prediction " + std::to_string(pred) +
                ", target " + std::to_string(target) + ", gradient " + std::to_string(grad) +
                ", mask " + std::to_string(mask) + " (expected " + std::to_string(pixels) +
                " pixels)");
  }
}

// Shared body of the per-pixel losses: f(residual) and its derivative, over counted pixels.
template <typename T, typename Value, typename Derivative>
double pointwise_loss(const char* name, std::span<const T> pred, std::span<const T> target,
                      int channels, std::span<const T> mask, std::span<T> grad, double weight,
                      bool needs_measurement, Value value, Derivative derivative) {
  if (channels < 1) throw Error(std::string(name) + ": channels is " + std::to_string(channels));
  const std::size_t pixels = pred.size() / static_cast<std::size_t>(channels);
  check_sizes<T>(name, pred.size(), target.size(), grad.size(), mask.size(), pixels);
  if (mask.empty() && !needs_measurement) {  // every element counts: one vectorized pass
    if (pred.empty()) return 0;
    const double scale = weight / static_cast<double>(pred.size());
    double sum = 0;
#pragma omp simd reduction(+ : sum)
    for (std::size_t i = 0; i < pred.size(); ++i) {
      const double r = double(pred[i]) - double(target[i]);
      sum += value(r);
      grad[i] += static_cast<T>(scale * derivative(r));
    }
    return sum * scale;
  }
  auto counted = [&](std::size_t p, std::size_t i) {
    return (mask.empty() || mask[p] > 0) && (!needs_measurement || target[i] > 0);
  };
  std::size_t count = 0;
  for (std::size_t p = 0; p < pixels; ++p)
    for (int c = 0; c < channels; ++c) count += counted(p, p * channels + c);
  if (count == 0) return 0;
  const double scale = weight / static_cast<double>(count);
  double sum = 0;
  for (std::size_t p = 0; p < pixels; ++p) {
    for (int c = 0; c < channels; ++c) {
      const std::size_t i = p * channels + c;
      if (!counted(p, i)) continue;
      const double r = double(pred[i]) - double(target[i]);
      sum += value(r);
      grad[i] += static_cast<T>(scale * derivative(r));
    }
  }
  return sum * scale;
}

double sign(double r) { return r > 0 ? 1.0 : (r < 0 ? -1.0 : 0.0); }

// Separable 11-tap Gaussian (sigma 1.5) blur with zero padding; symmetric, so it is also its
// own adjoint. In the loss's own precision: float halves the work of the float loss (16 lanes
// instead of 8), and the statistics it blurs are within [0, 1].
constexpr int kRadius = 5;
template <typename A>
struct Window {
  A w[2 * kRadius + 1];
  Window() {
    double taps[2 * kRadius + 1], sum = 0;
    for (int i = -kRadius; i <= kRadius; ++i) sum += taps[i + kRadius] = std::exp(-i * i / (2 * 1.5 * 1.5));
    for (int i = 0; i <= 2 * kRadius; ++i) w[i] = static_cast<A>(taps[i] / sum);
  }
};

// `tmp` is scratch of the image's size; `out` is overwritten.
template <typename A>
void blur(const std::vector<A>& in, std::vector<A>& out, std::vector<A>& tmp, int width, int height) {
  static const Window<A> window;
  tmp.assign(in.size(), A(0));
  out.assign(in.size(), A(0));
  // Horizontal: tap by tap over the pixels it reaches (taps outside the row are zero padding),
  // so the pixel loop vectorizes; each pixel still sums its taps in order.
  for (int y = 0; y < height; ++y) {
    const A* row = &in[std::size_t(y) * width];
    A* dst = &tmp[std::size_t(y) * width];
    for (int k = -kRadius; k <= kRadius; ++k) {
      const A w = window.w[k + kRadius];
      for (int x = std::max(0, -k); x < std::min(width, width - k); ++x) dst[x] += w * row[x + k];
    }
  }
  // Vertical: the same, whole rows at a time.
  for (int y = 0; y < height; ++y) {
    A* dst = &out[std::size_t(y) * width];
    for (int k = -kRadius; k <= kRadius; ++k) {
      const int yy = y + k;
      if (yy < 0 || yy >= height) continue;
      const A w = window.w[k + kRadius];
      const A* src = &tmp[std::size_t(yy) * width];
      for (int x = 0; x < width; ++x) dst[x] += w * src[x];
    }
  }
}

}  // namespace

template <typename T>
double l1_loss(std::span<const T> pred, std::span<const T> target, int channels,
               std::span<const T> mask, std::span<T> grad, double weight) {
  return pointwise_loss<T>("l1_loss", pred, target, channels, mask, grad, weight, false,
                           [](double r) { return std::abs(r); }, sign);
}

template <typename T>
double l2_loss(std::span<const T> pred, std::span<const T> target, int channels,
               std::span<const T> mask, std::span<T> grad, double weight) {
  return pointwise_loss<T>("l2_loss", pred, target, channels, mask, grad, weight, false,
                           [](double r) { return r * r; }, [](double r) { return 2 * r; });
}

template <typename T>
double depth_l1_loss(std::span<const T> pred, std::span<const T> target, std::span<const T> mask,
                     std::span<T> grad, double weight) {
  return pointwise_loss<T>("depth_l1_loss", pred, target, 1, mask, grad, weight, true,
                           [](double r) { return std::abs(r); }, sign);
}

template <typename T>
double silhouette_depth_l1_loss(std::span<const T> depth, std::span<const T> alpha,
                                std::span<const T> target, double alpha_threshold,
                                std::span<T> grad_depth, std::span<T> grad_alpha, double weight) {
  const char* name = "silhouette_depth_l1_loss";
  check_sizes<T>(name, depth.size(), target.size(), grad_depth.size(), alpha.size(), depth.size());
  check_sizes<T>(name, depth.size(), target.size(), grad_alpha.size(), 0, depth.size());
  const std::size_t count = static_cast<std::size_t>(std::count_if(target.begin(), target.end(), [](T t) { return t > 0; }));
  if (count == 0) return 0;
  const double scale = weight / static_cast<double>(count);
  double sum = 0;
  for (std::size_t p = 0; p < depth.size(); ++p) {
    if (!(target[p] > 0)) continue;
    const bool normalized = alpha[p] > alpha_threshold;
    const double a = alpha[p], pred = normalized ? depth[p] / a : depth[p];
    const double r = pred - target[p], g = scale * sign(r);
    sum += std::abs(r);
    if (normalized) {  // d(D/A)/dD = 1/A, d(D/A)/dA = -(D/A)/A
      grad_depth[p] += static_cast<T>(g / a);
      grad_alpha[p] -= static_cast<T>(g * pred / a);
    } else {
      grad_depth[p] += static_cast<T>(g);
    }
  }
  return scale * sum;
}

template <typename T>
double dssim_loss(std::span<const T> pred, std::span<const T> target, int width, int height,
                  int channels, std::span<T> grad, double weight, ThreadPool* pool) {
  const std::size_t pixels = static_cast<std::size_t>(width) * height;
  if (width < 1 || height < 1 || channels < 1) throw Error("dssim_loss: empty image");
  check_sizes<T>("dssim_loss", pred.size(), target.size(), grad.size(), 0, pixels);
  if (pred.size() != pixels * channels) throw Error("dssim_loss: image size does not match " + std::to_string(width) + "x" + std::to_string(height));
  constexpr T kC1 = T(0.01 * 0.01), kC2 = T(0.03 * 0.03);
  const T scale = static_cast<T>(weight / static_cast<double>(pixels * channels));
  const std::size_t planes = static_cast<std::size_t>(channels);
  // The work comes in independent items (blurs, bands of rows), each computing what the
  // serial order computed, so the result is the same with any number of threads.
  const std::size_t bands = std::min<std::size_t>(static_cast<std::size_t>(height), 16);
  auto band_rows = [&](std::size_t b) {
    return std::pair{pixels * b / bands / width * width, pixels * (b + 1) / bands / width * width};
  };
  // The local statistics of each channel: blurs of x, y, x^2, y^2 and xy.
  enum Stat { kMx, kMy, kExx, kEyy, kExy, kStats };
  std::vector<std::vector<T>> stats(planes * kStats), scratch(planes * kStats);
  parallel_for(pool, planes * kStats, [&](std::size_t item) {
    const std::size_t c = item / kStats;
    const Stat stat = static_cast<Stat>(item % kStats);
    std::vector<T>& in = scratch[item];
    in.resize(pixels);
    for (std::size_t p = 0; p < pixels; ++p) {
      const T x = pred[p * planes + c], y = target[p * planes + c];
      in[p] = stat == kMx ? x : stat == kMy ? y : stat == kExx ? x * x : stat == kEyy ? y * y : x * y;
    }
    std::vector<T> tmp;
    blur(in, stats[item], tmp, width, height);
  });
  // SSIM per pixel, and dS/d(mu_x), dS/d(E[x^2]) and dS/d(E[xy]) times dLoss/dS = -scale.
  std::vector<T> ssim(pixels * planes);
  enum Partial { kDa, kDb, kDc, kPartials };
  std::vector<std::vector<T>> partials(planes * kPartials, std::vector<T>(pixels));
  parallel_for(pool, planes * bands, [&](std::size_t item) {
    const std::size_t c = item / bands;
    const auto [begin, end] = band_rows(item % bands);
    const std::vector<T>* st = &stats[c * kStats];
    const T *mx = st[kMx].data(), *my = st[kMy].data(), *exx = st[kExx].data(), *eyy = st[kEyy].data(), *exy = st[kExy].data();
    T *da = partials[c * kPartials + kDa].data(), *db = partials[c * kPartials + kDb].data(), *dc = partials[c * kPartials + kDc].data();
    for (std::size_t p = begin; p < end; ++p) {
      const T a1 = 2 * mx[p] * my[p] + kC1, a2 = 2 * (exy[p] - mx[p] * my[p]) + kC2;
      const T b1 = mx[p] * mx[p] + my[p] * my[p] + kC1;
      const T b2 = exx[p] - mx[p] * mx[p] + eyy[p] - my[p] * my[p] + kC2;
      const T inv_b = 1 / (b1 * b2);
      const T s = a1 * a2 * inv_b;
      ssim[c * pixels + p] = s;
      // Written without dividing by a1 or a2: a2 (twice the covariance plus C2) can be exactly
      // 0, and s / a2 as s * (1 / a2) is then 0 * inf.
      da[p] = -scale * (2 * my[p] * (a2 - a1) * inv_b + s * (2 * mx[p] / b2 - 2 * mx[p] / b1));
      db[p] = -scale * s * (-1 / b2);
      dc[p] = -scale * 2 * a1 * inv_b;
    }
  });
  // The local statistics are blurs of x, x^2 and xy; the blur is its own adjoint.
  parallel_for(pool, planes * kPartials, [&](std::size_t item) {
    std::vector<T> tmp;
    blur(partials[item], scratch[item], tmp, width, height);
  });
  parallel_for(pool, bands, [&](std::size_t b) {
    const auto [begin, end] = band_rows(b);
    for (std::size_t c = 0; c < planes; ++c) {
      const T *ga = scratch[c * kPartials + kDa].data(), *gb = scratch[c * kPartials + kDb].data(), *gc = scratch[c * kPartials + kDc].data();
      for (std::size_t p = begin; p < end; ++p) {
        const T x = pred[p * planes + c], y = target[p * planes + c];
        grad[p * planes + c] += ga[p] + 2 * x * gb[p] + y * gc[p];
      }
    }
  });
  double ssim_sum = 0;  // in one fixed order
  for (const T s : ssim) ssim_sum += s;
  return weight * (1 - ssim_sum / static_cast<double>(pixels * channels));
}

template <typename T>
void alpha_mask(std::span<const T> alpha, T threshold, std::span<T> mask) {
  if (alpha.size() != mask.size()) throw Error("alpha_mask: alpha and mask sizes differ");
  for (std::size_t i = 0; i < alpha.size(); ++i) mask[i] = alpha[i] > threshold ? T(1) : T(0);
}

double psnr(std::span<const float> pred, std::span<const float> target, int channels,
            std::span<const float> mask) {
  std::vector<float> grad(pred.size(), 0.f);
  const double mse = l2_loss<float>(pred, target, channels, mask, grad);
  return mse > 0 ? -10.0 * std::log10(mse) : INFINITY;
}

#define GSLAM_INSTANTIATE(T)                                                                       \
  template double l1_loss(std::span<const T>, std::span<const T>, int, std::span<const T>,        \
                          std::span<T>, double);                                                  \
  template double l2_loss(std::span<const T>, std::span<const T>, int, std::span<const T>,        \
                          std::span<T>, double);                                                  \
  template double depth_l1_loss(std::span<const T>, std::span<const T>, std::span<const T>,       \
                                std::span<T>, double);                                            \
  template double silhouette_depth_l1_loss(std::span<const T>, std::span<const T>,              \
                                           std::span<const T>, double, std::span<T>, std::span<T>, \
                                           double);                                              \
  template double dssim_loss(std::span<const T>, std::span<const T>, int, int, int, std::span<T>, \
                             double, ThreadPool*);                                                \
  template void alpha_mask(std::span<const T>, T, std::span<T>);
GSLAM_INSTANTIATE(float)
GSLAM_INSTANTIATE(double)
#undef GSLAM_INSTANTIATE

}  // namespace splat
