// The final refinement's blur model (mapping::ExposureMotion): a frame blurred by the camera's
// motion is fitted as the mean of views across its exposure, so the map it leaves renders the
// scene sharp rather than painted with the frame's blur.
#include <algorithm>
#include <cmath>
#include <filesystem>

#include <gtest/gtest.h>

#include "datasets/dataset.h"
#include "datasets/synthetic_sequence.h"
#include "mapping/mapper.h"
#include "splat/error.h"
#include "splat/losses.h"
#include "splat/rasterizer.h"
#include "splat/rgbd_frame.h"
#include "splat/se3.h"
#include "support/synthetic_dataset.h"
#include "support/temp_dir.h"

namespace {

// The generated sequence the tests draw from: few frames, since under qemu (arm64) and the
// sanitizers each rendered view counts. `blur_samples` views are averaged across each exposure.
app::SyntheticOptions sequence_options(int blur_samples) {
  app::SyntheticOptions o;
  o.frames = 6;
  o.shake_peak_rate = 3.0;
  o.exposure = 1.0 / 30;
  o.blur_samples = blur_samples;
  return o;
}

// A generated sequence and the frame turning fastest, with its motion over the exposure from its
// neighbours' true poses.
struct FastestFrame {
  app::Dataset sequence;
  std::size_t index = 1;
  splat::Vector6d twist = splat::Vector6d::Zero();
};

FastestFrame fastest_frame(const std::filesystem::path& dir, int blur_samples) {
  const app::SyntheticOptions o = sequence_options(blur_samples);
  FastestFrame b{gslam::test::synthetic_dataset(dir, o)};
  auto pose = [&](std::size_t i) { return *b.sequence.entries[i].T_world_cam_truth; };
  for (std::size_t i = 1; i + 1 < b.sequence.entries.size(); ++i) {
    const double dt = b.sequence.entries[i + 1].timestamp - b.sequence.entries[i - 1].timestamp;
    const splat::Vector6d t = splat::se3_log(pose(i - 1).inverse() * pose(i + 1)) * (o.exposure / dt);
    if (t.tail<3>().norm() > b.twist.tail<3>().norm()) b.index = i, b.twist = t;
  }
  return b;
}

// The map a keyframe of the frame seeds, then refined on it `iterations` times through `motion`.
splat::Gaussians refined_map(splat::Rasterizer& rasterizer, const splat::RgbdFrame& frame, const Eigen::Isometry3d& T_cam_world,
                             int iterations, const mapping::ExposureMotion& motion) {
  mapping::MapperConfig config;
  config.iterations = 0;
  mapping::Mapper mapper(rasterizer, config);
  mapper.add_keyframe(frame, T_cam_world);
  Eigen::Isometry3d at = T_cam_world;
  mapper.refine(mapper.refinement_frame(frame), at, nullptr, iterations, false, std::nullopt, motion);
  return mapper.map();
}

// The fastest-turning frame of a generated sequence, at its true pose, and a CPU rasterizer. Only
// the sharper-map test needs its frames blurred (eight views each); the model's other checks take
// them unblurred, at an eighth of the cost.
class BlurModel : public ::testing::Test {
 protected:
  void generate(int blur_samples) {
    b = fastest_frame(dir / "generated", blur_samples);
    T_cam_world = b.sequence.entries[b.index].T_world_cam_truth->inverse();
    frame = b.sequence.load(b.index);
  }
  gslam::test::TempDir dir;
  std::unique_ptr<splat::Rasterizer> rasterizer = splat::make_cpu_rasterizer();
  FastestFrame b;
  Eigen::Isometry3d T_cam_world;
  splat::RgbdFrame frame;
};

TEST_F(BlurModel, FramesFittedThroughTheirMotionLeaveASharperMap) {
  generate(8);
  // The same poses, one view each.
  const app::Dataset sharp = gslam::test::synthetic_dataset(dir / "sharp", sequence_options(1));
  const splat::RgbdFrame truth = splat::downsample(sharp.load(b.index), mapping::MapperConfig{}.refine_resolution_factor);
  auto psnr_against_truth = [&](const splat::Gaussians& map) {
    const splat::ForwardResult r = rasterizer->forward(map, splat::posed(truth.camera, T_cam_world), splat::images_only());
    return splat::psnr(r.rgb, truth.rgb, 3);
  };
  const double blur_px = truth.camera.fx * b.twist.tail<3>().norm();
  ASSERT_GT(blur_px, 4) << "the generated frame must be blurred for the test to mean anything";
  const double plain_db = psnr_against_truth(refined_map(*rasterizer, frame, T_cam_world, 150, {}));
  const double modelled_db = psnr_against_truth(refined_map(*rasterizer, frame, T_cam_world, 150, {b.twist, 4}));
  std::printf("frame %zu, %.1f px of blur: against the sharp frame %.2f dB fitted plainly, %.2f dB through its motion\n",
              b.index, blur_px, plain_db, modelled_db);
  EXPECT_GT(modelled_db, plain_db + 1.0);
}

// Views that do not move average to the one view: the same map as no model at all.
TEST_F(BlurModel, ViewsThatDoNotMoveGiveThePlainMap) {
  generate(1);
  const splat::Gaussians plain = refined_map(*rasterizer, frame, T_cam_world, 5, {});
  const splat::Gaussians still = refined_map(*rasterizer, frame, T_cam_world, 5, {splat::Vector6d::Zero(), 4});
  ASSERT_EQ(still.size(), plain.size());
  for (std::size_t i = 0; i < plain.means.size(); ++i) ASSERT_NEAR(still.means[i], plain.means[i], 1e-4f) << i;
  for (std::size_t i = 0; i < plain.sh.size(); ++i) ASSERT_NEAR(still.sh[i], plain.sh[i], 1e-3f) << i;
}

// A motion the views cannot be placed along is refused before anything changes.
TEST_F(BlurModel, RefusesAMotionWithoutViewsOrNotFinite) {
  generate(1);
  splat::Vector6d nan_twist = splat::Vector6d::Zero();
  nan_twist[3] = std::nan("");
  EXPECT_THROW(refined_map(*rasterizer, frame, T_cam_world, 1, {splat::Vector6d::Zero(), 0}), splat::Error);
  EXPECT_THROW(refined_map(*rasterizer, frame, T_cam_world, 1, {nan_twist, 2}), splat::Error);
}

}  // namespace
