#pragma once
#include <span>

namespace splat {

class ThreadPool;

// Image losses with their gradients. Images are flat [H, W, C]. Each function returns the
// weighted loss and ADDS weight * dLoss/dprediction into `grad` (same shape as the prediction),
// so several losses can share one gradient buffer. `mask` is [H, W] (empty = every pixel);
// a pixel counts where mask > 0. Means are over the counted pixels and channels; with no counted
// pixel the loss is 0. Sizes are checked (splat::Error).

// mean |pred - target|
template <typename T>
double l1_loss(std::span<const T> pred, std::span<const T> target, int channels,
               std::span<const T> mask, std::span<T> grad, double weight = 1.0);

// mean (pred - target)^2
template <typename T>
double l2_loss(std::span<const T> pred, std::span<const T> target, int channels,
               std::span<const T> mask, std::span<T> grad, double weight = 1.0);

// Depth L1 over pixels with a measurement (target > 0) and mask > 0: mean |pred - target|.
template <typename T>
double depth_l1_loss(std::span<const T> pred, std::span<const T> target, std::span<const T> mask,
                     std::span<T> grad, double weight = 1.0);

// Depth L1 over pixels with a measurement, mean |pred - target|, where pred is the
// alpha-normalized depth D / A where the silhouette A exceeds alpha_threshold and the
// alpha-weighted D elsewhere. D reads short wherever A < 1, a bias that pulls camera poses
// along their axis; D / A has none, while D on thin silhouettes still grows coverage.
// Adds the gradients with respect to D (ForwardResult::depth) and A to grad_depth, grad_alpha.
template <typename T>
double silhouette_depth_l1_loss(std::span<const T> depth, std::span<const T> alpha,
                                std::span<const T> target, double alpha_threshold,
                                std::span<T> grad_depth, std::span<T> grad_alpha,
                                double weight = 1.0);

// 1 - SSIM, SSIM averaged over pixels and channels, with an 11x11 Gaussian window (sigma 1.5),
// zero padding at the borders and C1 = 0.01^2, C2 = 0.03^2 (the 3DGS training loss). With a
// pool its blurs run on the pool's threads, with the same result.
template <typename T>
double dssim_loss(std::span<const T> pred, std::span<const T> target, int width, int height,
                  int channels, std::span<T> grad, double weight = 1.0, ThreadPool* pool = nullptr);

// Mask of pixels whose rendered alpha exceeds `threshold` (1 or 0), [H, W].
template <typename T>
void alpha_mask(std::span<const T> alpha, T threshold, std::span<T> mask);

// Peak signal-to-noise ratio in dB for values in [0, 1] (over the mask, if given).
double psnr(std::span<const float> pred, std::span<const float> target, int channels,
            std::span<const float> mask = {});

}  // namespace splat
