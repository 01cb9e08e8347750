// The final refinement's learning rate per call (Mapper::refine's learning_rate_scale): the
// sweep's coarse passes take larger steps than its last ones.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "datasets/dataset.h"
#include "datasets/synthetic_sequence.h"
#include "mapping/mapper.h"
#include "splat/error.h"
#include "splat/rasterizer.h"
#include "support/synthetic_dataset.h"
#include "support/temp_dir.h"

namespace {

class RefineRate : public ::testing::Test {
 protected:
  // The means of the map a keyframe of the frame seeds, after one refinement step at `scale`.
  std::vector<float> means_after_one_step(std::optional<double> scale) {
    mapping::MapperConfig config;
    config.iterations = 0;
    mapping::Mapper mapper(*rasterizer, config);
    mapper.add_keyframe(frame, T_cam_world);
    seeded = mapper.map().means;
    Eigen::Isometry3d pose = T_cam_world;
    mapper.refine(mapper.refinement_frame(frame), pose, nullptr, 1, false, std::nullopt, {}, scale);
    return mapper.map().means;
  }
  double moved(const std::vector<float>& means) const {
    double sum = 0;
    for (std::size_t k = 0; k < means.size(); ++k) sum += std::abs(double(means[k]) - seeded[k]);
    return sum;
  }

  gslam::test::TempDir dir;
  const app::Dataset dataset = [this] {
    app::SyntheticOptions o;
    o.frames = 1;
    return gslam::test::synthetic_dataset(dir / "seq", o);
  }();
  const splat::RgbdFrame frame = dataset.load(0);
  const Eigen::Isometry3d T_cam_world = dataset.entries[0].T_world_cam_truth->inverse();
  std::unique_ptr<splat::Rasterizer> rasterizer = splat::make_cpu_rasterizer({1});
  std::vector<float> seeded;
};

// Adam's first step is the rate times the gradient's sign (nearly): twice the scale, twice the
// distance. No scale is the configured refine_learning_rate_scale.
TEST_F(RefineRate, TheFirstStepMovesTheMapInProportionToTheScale) {
  const double configured = mapping::MapperConfig{}.refine_learning_rate_scale;
  const std::vector<float> by_default = means_after_one_step(std::nullopt);
  EXPECT_EQ(means_after_one_step(configured), by_default);
  const double base = moved(by_default);
  ASSERT_GT(base, 0) << "the step moved nothing";
  const double doubled = moved(means_after_one_step(2 * configured));
  EXPECT_NEAR(doubled / base, 2.0, 0.02);
}

TEST_F(RefineRate, RefusesAScaleThatIsNotPositiveAndFinite) {
  for (const double bad : {0.0, -1.0, std::numeric_limits<double>::quiet_NaN(),
                           std::numeric_limits<double>::infinity()}) {
    EXPECT_THROW(means_after_one_step(bad), splat::Error) << bad;
  }
}

}  // namespace
