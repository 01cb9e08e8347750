// Every loss against central differences in double, and its values on known inputs.
#include <algorithm>
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "splat/losses.h"
#include "splat/thread_pool.h"
#include "support/expect_error.h"
#include "support/gradient_check.h"

namespace {

struct Images {
  int width = 13, height = 9, channels = 3;
  std::vector<double> pred, target, mask;
};

Images random_images(uint32_t seed, int channels = 3) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.05, 0.95);
  Images im;
  im.channels = channels;
  const std::size_t n = static_cast<std::size_t>(im.width) * im.height * channels;
  for (std::size_t i = 0; i < n; ++i) {
    im.pred.push_back(u(rng));
    im.target.push_back(u(rng));
  }
  for (int p = 0; p < im.width * im.height; ++p) im.mask.push_back(u(rng) > 0.3 ? 1.0 : 0.0);
  return im;
}

using LossFn = std::function<double(std::span<const double>, std::span<double>)>;

void check_loss(const std::string& name, Images& im, const LossFn& loss) {
  std::vector<double> grad(im.pred.size(), 0.0);
  loss(im.pred, grad);
  std::vector<double> scratch(im.pred.size());
  gslam::test::expect_gradients_match(
      name, grad, [&](std::size_t i, double d) { im.pred[i] += d; },
      [&] { return std::vector<double>{loss(im.pred, scratch)}; });
}

TEST(Losses, GradientsMatchFiniteDifferences) {
  Images im = random_images(5);
  check_loss("l1", im, [&](auto p, auto g) { return splat::l1_loss<double>(p, im.target, 3, {}, g); });
  check_loss("l1_masked", im, [&](auto p, auto g) { return splat::l1_loss<double>(p, im.target, 3, im.mask, g, 0.7); });
  check_loss("l2_masked", im, [&](auto p, auto g) { return splat::l2_loss<double>(p, im.target, 3, im.mask, g); });
  check_loss("dssim", im, [&](auto p, auto g) { return splat::dssim_loss<double>(p, im.target, im.width, im.height, 3, g, 0.2); });
  Images depth = random_images(6, 1);
  for (std::size_t i = 0; i < depth.target.size(); i += 4) depth.target[i] = 0;  // no measurement
  check_loss("depth_l1", depth, [&](auto p, auto g) { return splat::depth_l1_loss<double>(p, depth.target, depth.mask, g); });
}

// The depth-and-silhouette loss in both of its inputs: depth D (pred) and alpha A, with pixels
// on both sides of the threshold and kept clear of it (a step there is not differentiable).
TEST(Losses, SilhouetteDepthGradientsMatchFiniteDifferences) {
  Images depth = random_images(7, 1);
  std::vector<double> alpha;
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> low(0.2, 0.8), high(0.96, 0.999);
  for (std::size_t p = 0; p < depth.pred.size(); ++p) alpha.push_back(p % 3 == 0 ? low(rng) : high(rng));
  for (std::size_t i = 0; i < depth.target.size(); i += 5) depth.target[i] = 0;  // no measurement
  constexpr double kThreshold = 0.9;
  auto loss = [&](std::span<double> g_depth, std::span<double> g_alpha) {
    return splat::silhouette_depth_l1_loss<double>(depth.pred, alpha, depth.target, kThreshold, g_depth, g_alpha, 0.8);
  };
  const std::size_t n = depth.pred.size();
  std::vector<double> g_depth(n, 0.0), g_alpha(n, 0.0), scratch_d(n), scratch_a(n);
  loss(g_depth, g_alpha);
  auto value = [&] { return std::vector<double>{loss(scratch_d, scratch_a)}; };
  gslam::test::expect_gradients_match("silhouette_depth d/dD", g_depth, [&](std::size_t i, double d) { depth.pred[i] += d; }, value);
  gslam::test::expect_gradients_match("silhouette_depth d/dA", g_alpha, [&](std::size_t i, double d) { alpha[i] += d; }, value);
  // Known value: normalized above the threshold, raw below; unmeasured pixels ignored.
  const std::vector<float> d = {1.0f, 1.0f, 2.0f}, a = {0.5f, 0.95f, 1.0f}, t = {0.8f, 1.0f, 0.f};
  std::vector<float> gd(3, 0.f), ga(3, 0.f);
  const double expected = (std::abs(1.0 - 0.8) + std::abs(1.0 / 0.95 - 1.0)) / 2;
  EXPECT_NEAR(splat::silhouette_depth_l1_loss<float>(d, a, t, kThreshold, gd, ga), expected, 1e-6);
  EXPECT_EQ(ga[0], 0.f) << "below the threshold alpha gets no gradient";
  EXPECT_EQ(gd[2], 0.f) << "no measurement, no gradient";
}

TEST(Losses, KnownValues) {
  const std::vector<float> pred = {0.5f, 0.5f, 1.0f, 0.0f}, target = {0.25f, 0.5f, 0.5f, 0.0f};
  std::vector<float> grad(4, 0.f);
  EXPECT_NEAR(splat::l1_loss<float>(pred, target, 1, {}, grad), 0.75 / 4, 1e-7);
  const std::vector<float> mask = {1, 0, 1, 0};
  std::fill(grad.begin(), grad.end(), 0.f);
  EXPECT_NEAR(splat::l2_loss<float>(pred, target, 1, mask, grad), (0.0625 + 0.25) / 2, 1e-7);
  EXPECT_EQ(grad[1], 0.f) << "masked pixels get no gradient";
  std::fill(grad.begin(), grad.end(), 0.f);
  // Depth: the zero target (no measurement) is ignored.
  EXPECT_NEAR(splat::depth_l1_loss<float>(pred, target, {}, grad), 0.75 / 3, 1e-7);
  EXPECT_EQ(grad[3], 0.f);
  std::fill(grad.begin(), grad.end(), 0.f);
  EXPECT_NEAR(splat::dssim_loss<float>(pred, pred, 2, 2, 1, grad), 0.0, 1e-9) << "identical images";
  const std::vector<double> pred_d(pred.begin(), pred.end());
  std::vector<double> grad_d(4, 0.0);
  EXPECT_NEAR(splat::dssim_loss<double>(pred_d, pred_d, 2, 2, 1, grad_d), 0.0, 1e-15) << "identical images, double";
  EXPECT_NEAR(splat::psnr(std::vector<float>(12, 0.5f), std::vector<float>(12, 0.6f), 3), 20.0, 1e-4);
}

// With a pool the D-SSIM splits its blurs and rows over threads: loss and gradient are the
// serial ones, bit for bit (results must not depend on the thread count). An odd size, so that
// bands of rows are uneven.
TEST(Losses, DssimOnThreadsEqualsSerial) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> u(0.f, 1.f);
  const int w = 37, h = 29;
  std::vector<float> pred(std::size_t(w) * h * 3), target(pred.size());
  for (std::size_t i = 0; i < pred.size(); ++i) pred[i] = u(rng), target[i] = u(rng);
  std::vector<float> serial(pred.size(), 0.25f), threaded(pred.size(), 0.25f);
  const double serial_loss = splat::dssim_loss<float>(pred, target, w, h, 3, serial, 0.2);
  splat::ThreadPool pool(3);
  const double threaded_loss = splat::dssim_loss<float>(pred, target, w, h, 3, threaded, 0.2, &pool);
  EXPECT_EQ(threaded_loss, serial_loss);
  EXPECT_GT(serial_loss, 0.01);
  EXPECT_EQ(threaded, serial);
}

// The float D-SSIM computes in float (the double one is the finite-difference-checked
// reference): loss and every gradient element agree with it on a photo-sized image.
TEST(Losses, FloatDssimAgreesWithDouble) {
  std::mt19937 rng(10);
  std::uniform_real_distribution<double> u(0.05, 0.95);
  const int w = 64, h = 48;
  std::vector<double> pred(std::size_t(w) * h * 3), target(pred.size());
  for (std::size_t i = 0; i < pred.size(); ++i) {
    target[i] = u(rng);
    pred[i] = std::clamp(target[i] + 0.2 * (u(rng) - 0.5), 0.0, 1.0);
  }
  std::vector<double> grad(pred.size(), 0.0);
  const double loss = splat::dssim_loss<double>(pred, target, w, h, 3, grad, 0.2);
  const std::vector<float> pred_f(pred.begin(), pred.end()), target_f(target.begin(), target.end());
  std::vector<float> grad_f(pred.size(), 0.f);
  EXPECT_NEAR(splat::dssim_loss<float>(pred_f, target_f, w, h, 3, grad_f, 0.2), loss, 1e-6 * loss);
  double largest = 0;
  for (double g : grad) largest = std::max(largest, std::abs(g));
  for (std::size_t i = 0; i < grad.size(); ++i) {
    ASSERT_NEAR(grad_f[i], grad[i], 1e-4 * largest) << "element " << i;
  }
}

TEST(Losses, RejectMismatchedSizes) {
  std::vector<float> a(6), b(5), g(6);
  GSLAM_EXPECT_ERROR(splat::l1_loss<float>(a, b, 3, {}, g), "l1_loss", "target 5");
  std::vector<float> mask(3);
  GSLAM_EXPECT_ERROR(splat::l1_loss<float>(a, a, 3, mask, g), "mask 3", "expected 2 pixels");
}

TEST(Losses, AlphaMaskThresholds) {
  const std::vector<float> alpha = {0.1f, 0.99f, 0.5f};
  std::vector<float> mask(3);
  splat::alpha_mask<float>(alpha, 0.5f, mask);
  EXPECT_EQ(mask, (std::vector<float>{0, 1, 0}));
}

}  // namespace
