// End to end: Gaussians seeded from a real TUM frame's depth are optimized until their render
// matches the photograph.
#include <algorithm>

#include <gtest/gtest.h>

#include "datasets/dataset.h"
#include "mapping/gaussian_adam.h"
#include "mapping/initialize.h"
#include "splat/losses.h"
#include "splat/rasterizer.h"
#include "support/test_data.h"

namespace {

TEST(PhotoFit, ReachesTwentyEightDecibelsOnARealFrame) {
  GSLAM_REQUIRE_SHARED_DATA(root, "tum_rgbd_fr3_teddy_first200/rgbd_dataset_freiburg3_teddy");
  const app::Dataset dataset = app::open_dataset(root);
  splat::RgbdFrame frame = splat::downsample(dataset.load(0), 2);  // 320x240
  // Pixels without a depth measurement get the farthest measured depth, so every pixel is seeded.
  const float far = *std::max_element(frame.depth.begin(), frame.depth.end());
  for (float& d : frame.depth) d = d > 0 ? d : far;
  splat::Gaussians map;
  mapping::SeedConfig seed;
  seed.stride = 4;  // one Gaussian per 16 pixels: the fit has to grow and shape them
  seed.scale_factor = 0.5;
  seed.opacity = 0.7;
  mapping::seed_from_depth(frame, Eigen::Isometry3d::Identity(), seed, map);
  ASSERT_GT(map.size(), 4000u);

  auto rasterizer = splat::make_cpu_rasterizer();
  mapping::AdamConfig config;
  config.means = 2e-4;  // metres: ~1/10000 of this 2 m scene per step
  mapping::GaussianAdam adam(config);
  const splat::Camera camera = splat::posed(frame.camera, Eigen::Isometry3d::Identity());
  constexpr int kMaxIterations = 300;  // the bound this test promises
  double psnr = 0, initial_psnr = 0;
  int iterations = 0;
  for (; iterations < kMaxIterations; ++iterations) {
    const splat::ForwardResult render = rasterizer->forward(map, camera, {});
    psnr = splat::psnr(render.rgb, frame.rgb, 3);
    if (iterations == 0) initial_psnr = psnr;
    if (psnr >= 28.0) break;
    splat::ImageGrads d;
    d.rgb.assign(render.rgb.size(), 0.f);
    splat::l1_loss<float>(render.rgb, frame.rgb, 3, {}, d.rgb, 0.8);
    splat::dssim_loss<float>(render.rgb, frame.rgb, frame.width(), frame.height(), 3, d.rgb, 0.2);
    adam.step(map, rasterizer->backward(render, d).d_gaussians);
  }
  std::printf("photo fit: %.2f dB -> %.2f dB after %d iterations with %zu Gaussians\n", initial_psnr, psnr,
              iterations, map.size());
  EXPECT_LT(initial_psnr, 24.0) << "the seeding alone should be far from the photograph";
  EXPECT_GE(psnr, 28.0) << "after " << kMaxIterations << " iterations";
}

}  // namespace
