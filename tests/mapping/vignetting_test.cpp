// The camera vignetting model: its gradient against central differences, and that the final
// refinement recovers a vignetting put into the frames.
#include <cmath>
#include <random>

#include <gtest/gtest.h>

#include "datasets/dataset.h"
#include "datasets/synthetic_sequence.h"
#include "mapping/mapper.h"
#include "mapping/vignetting.h"
#include "splat/error.h"
#include "splat/rasterizer.h"
#include "support/synthetic_dataset.h"
#include "support/temp_dir.h"

namespace {

splat::Camera small_camera() {
  splat::Camera c;
  c.width = 8, c.height = 6, c.fx = 6, c.fy = 5, c.cx = 3.7, c.cy = 2.9;
  return c;
}

TEST(Vignetting, GainIsOneAtThePrincipalPointAndFollowsTheRadius) {
  const mapping::Vignetting v{0.2, -0.05};
  EXPECT_EQ(v.gain(0, 0), 1.0);
  EXPECT_NEAR(v.gain(0.6, 0.8), 1 + 0.2 - 0.05, 1e-12);  // r = 1
  std::vector<float> rgb(8 * 6 * 3, 0.5f);
  v.apply(rgb, small_camera());
  const splat::Camera c = small_camera();
  const double u = (7 + 0.5 - c.cx) / c.fx, w = (5 + 0.5 - c.cy) / c.fy;  // the last pixel
  EXPECT_NEAR(rgb.back(), 0.5 * v.gain(u, w), 1e-6);
}

TEST(Vignetting, BackwardMatchesCentralDifferences) {
  const splat::Camera c = small_camera();
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> unit(0.f, 1.f);
  std::vector<float> radiance(8 * 6 * 3), target(radiance.size());
  for (std::size_t i = 0; i < radiance.size(); ++i) radiance[i] = unit(rng), target[i] = unit(rng);
  // L = sum (recorded - target)^2 / 2, so dL/d(recorded) = recorded - target.
  auto loss = [&](const mapping::Vignetting& v) {
    std::vector<float> recorded = radiance;
    v.apply(recorded, c);
    double l = 0;
    for (std::size_t i = 0; i < recorded.size(); ++i) l += 0.5 * (recorded[i] - target[i]) * (recorded[i] - target[i]);
    return l;
  };
  const mapping::Vignetting v{0.3, -0.1};
  std::vector<float> d_rgb = radiance;
  v.apply(d_rgb, c);
  for (std::size_t i = 0; i < d_rgb.size(); ++i) d_rgb[i] -= target[i];
  const std::vector<float> d_recorded = d_rgb;
  const std::array<double, 2> d_k = v.backward(radiance, d_rgb, c);
  const double h = 1e-3;
  EXPECT_NEAR(d_k[0], (loss({v.k1 + h, v.k2}) - loss({v.k1 - h, v.k2})) / (2 * h), 1e-4 * std::abs(d_k[0]) + 1e-6);
  EXPECT_NEAR(d_k[1], (loss({v.k1, v.k2 + h}) - loss({v.k1, v.k2 - h})) / (2 * h), 1e-4 * std::abs(d_k[1]) + 1e-6);
  // dL/d(radiance) is dL/d(recorded) times the gain.
  const double u = (0.5 - c.cx) / c.fx, w = (0.5 - c.cy) / c.fy;  // pixel 0
  EXPECT_NEAR(d_rgb[0], d_recorded[0] * v.gain(u, w), 1e-6);
}

TEST(Vignetting, RejectsAnImageOfTheWrongSize) {
  std::vector<float> rgb(10);
  EXPECT_THROW(mapping::Vignetting{}.apply(rgb, small_camera()), splat::Error);
}

// Frames darkened towards their corners (k1 = -0.3): the final refinement learns a fall-off
// the true way, while on the same frames without one it learns next to none. (The map takes up
// part of the fall-off while keyframes are mapped, before any is learned, and on this short
// synthetic sequence the two fit the frames equally well; on teddy, learning it raised PSNR
// by 0.5 dB.)
TEST(Vignetting, RefinementLearnsTheFramesFallOffAndNoneWhereThereIsNone) {
  gslam::test::TempDir dir;
  app::SyntheticOptions o;
  const app::Dataset dataset = gslam::test::synthetic_dataset(dir / "seq", o);
  // Every sixth frame: the same surfaces at different places in the image, which is what tells
  // the fall-off from the surfaces' colours.
  std::vector<std::size_t> frames;
  for (std::size_t i = 0; i < dataset.entries.size(); i += 6) frames.push_back(i);
  auto rasterizer = splat::make_cpu_rasterizer();
  auto learn = [&](const mapping::Vignetting& truth) {
    auto load = [&](std::size_t i) {
      splat::RgbdFrame f = dataset.load(i);
      truth.apply(f.rgb, f.camera);
      return f;
    };
    mapping::MapperConfig config;
    config.iterations = 10;
    config.refine_vignetting_rate = 2e-2;
    mapping::Mapper mapper(*rasterizer, config);
    for (const std::size_t i : frames) mapper.add_keyframe(load(i), dataset.entries[i].T_world_cam_truth->inverse());
    for (int pass = 0; pass < 20; ++pass) {
      for (const std::size_t i : frames) {
        Eigen::Isometry3d pose = dataset.entries[i].T_world_cam_truth->inverse();
        mapper.refine(mapper.refinement_frame(load(i)), pose, nullptr, 1);
      }
    }
    return mapper.vignetting();
  };
  const splat::Camera& c = dataset.load(0).camera;
  const double u = c.width / 2.0 / c.fx, w = c.height / 2.0 / c.fy;  // an image corner
  const mapping::Vignetting truth{-0.3, 0};
  const mapping::Vignetting learned = learn(truth), learned_from_none = learn({});
  std::printf("corner gain learned %.3f (k1 %.3f, k2 %.3f) from frames made with %.3f; %.3f from frames without\n",
              learned.gain(u, w), learned.k1, learned.k2, truth.gain(u, w), learned_from_none.gain(u, w));
  EXPECT_LT(learned.gain(u, w), 1 - 0.4 * (1 - truth.gain(u, w)));
  EXPECT_GT(learned.gain(u, w), truth.gain(u, w) - 0.1);
  EXPECT_NEAR(learned_from_none.gain(u, w), 1, 0.2 * (1 - truth.gain(u, w)));
}

}  // namespace
