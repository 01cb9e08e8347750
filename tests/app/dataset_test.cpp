#include <cmath>
#include <cstdio>

#include <gtest/gtest.h>

#include "datasets/dataset.h"
#include "commands/evaluation.h"
#include "io/image_io.h"
#include "datasets/synthetic_sequence.h"
#include "splat/se3.h"
#include "support/expect_error.h"
#include "support/temp_dir.h"
#include "support/test_data.h"

namespace {

using gslam::test::TempDir;

// A 3-frame, 64x48 synthetic sequence in TUM layout (f = 52).
void write_small_sequence(const std::filesystem::path& dir) {
  app::SyntheticOptions o;
  o.frames = 3;
  o.width = 64;
  o.height = 48;
  o.focal = 52;
  app::write_synthetic_sequence(dir, o);
}

TEST(Association, PairsNearestWithinTwentyMillisecondsOnce) {
  const std::vector<double> rgb = {0.00, 0.033, 0.066, 0.100};
  const std::vector<double> depth = {0.005, 0.030, 0.031, 0.150};
  const auto pairs = app::associate(rgb, depth);
  // 0.00-0.005, 0.033-0.031 (closest), 0.066 has none within 0.02 (0.030 is taken), 0.100 none.
  ASSERT_EQ(pairs.size(), 2u);
  EXPECT_EQ(pairs[0], std::make_pair(std::size_t{0}, std::size_t{0}));
  EXPECT_EQ(pairs[1], std::make_pair(std::size_t{1}, std::size_t{2}));
}

TEST(TumDataset, RealSequenceSkipsMissingFilesAndFindsGroundTruth) {
  GSLAM_REQUIRE_SHARED_DATA(root, "tum_rgbd_fr3_teddy_first200/rgbd_dataset_freiburg3_teddy");
  const app::Dataset d = app::open_dataset(root);
  EXPECT_EQ(d.format, "tum");
  EXPECT_DOUBLE_EQ(d.intrinsics.fx, 535.4);  // freiburg3 preset from the folder name
  EXPECT_EQ(d.intrinsics.width, 640);
  EXPECT_GT(d.skipped_missing, 4000u) << "rgb.txt/depth.txt list the whole sequence";
  EXPECT_EQ(d.entries.size(), 193u) << "SOURCE.md: 193 colour frames have depth within 20 ms";
  // The folder holds the first 200 of the 2409 listed frames: a subset, reported, not a warning.
  EXPECT_EQ(d.listed, 2409u);
  EXPECT_EQ(d.missing_colour, 2209u);
  EXPECT_EQ(d.unmatched, 7u);
  EXPECT_EQ(
      d.frames_used(),
      "193 frames used (of 2409 listed; 2209 have no colour image here, 7 no depth within 0.02 s)");
  EXPECT_TRUE(d.warnings.empty()) << d.warnings.front();
  std::size_t with_truth = 0;
  for (const auto& e : d.entries) with_truth += e.T_world_cam_truth.has_value();
  EXPECT_EQ(with_truth, 189u) << "SOURCE.md: 189 also have ground truth";
  const splat::RgbdFrame f = d.load(0);
  std::size_t valid = 0;
  for (float z : f.depth) valid += z > 0;
  EXPECT_NEAR(static_cast<double>(valid) / static_cast<double>(f.depth.size()), 0.74, 0.02) << "SOURCE.md: 74% valid depth";
}

TEST(TumDataset, UnknownCameraAndBadFoldersAreErrors) {
  TempDir dir;
  std::filesystem::create_directories(dir / "mystery");
  gslam::test::write_text(dir / "mystery" / "rgb.txt", "1.0 rgb/1.png\n");
  gslam::test::write_text(dir / "mystery" / "depth.txt", "1.0 depth/1.png\n");
  GSLAM_EXPECT_ERROR(app::open_dataset(dir / "mystery"), "unknown TUM camera", "--intrinsics");
  GSLAM_EXPECT_ERROR(app::open_dataset(dir / "nothing"), "nothing", "does not exist");
  GSLAM_EXPECT_ERROR(app::open_dataset(dir.path()), "not a dataset folder");
  GSLAM_EXPECT_ERROR(app::open_dataset(dir / "mystery"), "or write intrinsics.txt");
  // With intrinsics given, the missing images leave no frame.
  app::DatasetOptions options;
  options.intrinsics = "500,500,320,240";
  GSLAM_EXPECT_ERROR(app::open_dataset(dir / "mystery", options), "no frame has both colour and depth");
}

// A folder matching no layout: one line naming every layout and what this folder lacks.
TEST(Dataset, UnknownFolderErrorNamesEveryLayoutAndWhatIsMissing) {
  TempDir dir;
  const std::vector<std::string> layouts = {
      "TUM RGB-D (rgb.txt + depth.txt",
      "groundtruth.txt",
      "--intrinsics",
      "intrinsics.txt 'fx fy cx cy'",
      "results/frameNNNNNN.jpg + results/depthNNNNNN.png + traj.txt",
      "docs/guide.md"};
  auto expect_error = [&](const std::filesystem::path& folder, const std::string& missing) {
    try {
      app::open_dataset(folder);
      ADD_FAILURE() << folder << ": no error";
    } catch (const splat::Error& e) {
      const std::string message = e.what();
      EXPECT_EQ(message.find('\n'), std::string::npos) << "one line: " << message;
      EXPECT_NE(message.find("not a dataset folder (" + missing + ")"), std::string::npos)
          << message;
      for (const auto& l : layouts)
        EXPECT_NE(message.find(l), std::string::npos) << "lacks '" << l << "': " << message;
    }
  };
  for (const char* folder : {"empty", "lists", "pngs", "other"})
    std::filesystem::create_directories(dir / folder);
  expect_error(dir / "empty", "is empty");
  gslam::test::write_text(dir / "lists" / "rgb.txt", "1.0 rgb/1.png\n");
  expect_error(dir / "lists", "has rgb.txt but no depth.txt");
  gslam::test::write_text(dir / "pngs" / "a.png", "");
  gslam::test::write_text(dir / "pngs" / "b.PNG", "");
  expect_error(dir / "pngs", "has 2 image files but no rgb.txt and depth.txt listing them");
  std::filesystem::create_directories(dir / "folders" / "rgb");
  std::filesystem::create_directories(dir / "folders" / "depth");
  expect_error(dir / "folders",
               "has rgb/ or depth/ but no rgb.txt and depth.txt listing their images");
  std::filesystem::create_directories(dir / "replica" / "results");
  expect_error(dir / "replica", "has results/ but no traj.txt");
  gslam::test::write_text(dir / "other" / "notes.md", "");
  expect_error(dir / "other", "has none of rgb.txt, depth.txt, traj.txt, results/");
}

// Where the listed frames went, and warnings only for real problems.
TEST(Dataset, CountsUnusedFramesAndWarnsOnGroundTruthFromAnotherClock) {
  TempDir dir;
  write_small_sequence(dir / "seq");
  const app::Dataset all = app::open_dataset(dir / "seq");
  EXPECT_EQ(all.frames_used(), "3 frames");
  EXPECT_TRUE(all.warnings.empty());
  app::DatasetOptions options;
  options.max_frames = 2;
  EXPECT_EQ(app::open_dataset(dir / "seq", options).frames_used(),
            "2 frames used (of 3 listed; 1 beyond --max-frames)");
  gslam::test::write_text(dir / "seq" / "groundtruth.txt",
                          "5000.0 0 0 0 0 0 0 1\n5001.0 0 0 0 0 0 0 1\n");
  const app::Dataset shifted = app::open_dataset(dir / "seq");
  EXPECT_FALSE(shifted.has_ground_truth());
  ASSERT_EQ(shifted.warnings.size(), 1u);
  EXPECT_NE(shifted.warnings[0].find("groundtruth.txt: no pose within 0.02 s of any frame"),
            std::string::npos)
      << shifted.warnings[0];
  // Lists naming no file here: the error says how many were listed and why none is used.
  gslam::test::write_text(dir / "seq" / "rgb.txt", "1.0 rgb/gone.png\n");
  GSLAM_EXPECT_ERROR(app::open_dataset(dir / "seq"),
                     "no frame has both colour and depth (1 listed: 1 have no colour image here)");
}

TEST(SyntheticSequence, WritesAReadableSequenceWithExactGroundTruth) {
  TempDir dir;
  write_small_sequence(dir / "seq");
  const app::Dataset d = app::open_dataset(dir / "seq");
  ASSERT_EQ(d.entries.size(), 3u);
  EXPECT_DOUBLE_EQ(d.intrinsics.fx, 52);
  EXPECT_TRUE(d.has_ground_truth());
  const splat::RgbdFrame f = d.load(1);
  for (float z : f.depth) ASSERT_GT(z, 0.f) << "the room is closed: every pixel hits something";
  float brightest = 0;
  for (float c : f.rgb) brightest = std::max(brightest, c);
  EXPECT_GT(brightest, 0.3f);
}

TEST(TrajectoryEvaluation, RigidlyMovedTrajectoryHasZeroAte) {
  std::vector<app::StampedPose> truth, estimate;
  const Eigen::Isometry3d offset = splat::se3_exp((splat::Vector6d() << 1, 2, 3, 0.3, -0.2, 0.5).finished());
  for (int i = 0; i < 40; ++i) {
    app::StampedPose p;
    p.timestamp = i * 0.05;
    p.T_world_cam = splat::se3_exp((splat::Vector6d() << 0.1 * i, std::sin(0.2 * i), 0.02 * i * i, 0.01 * i, 0.02, -0.01 * i).finished());
    truth.push_back(p);
    p.T_world_cam = offset * p.T_world_cam;
    p.timestamp += 0.004;  // within the association window
    estimate.push_back(p);
  }
  const app::TrajectoryErrors e = app::evaluate_trajectory(estimate, truth);
  EXPECT_EQ(e.matched, 40u);
  EXPECT_LT(e.ate_rmse, 1e-9);
  EXPECT_LT(e.rpe_translation_rmse, 1e-9);
  EXPECT_GT(e.rpe_pairs, 0u);
  // A 1 cm error on every position in x shows up as ~1 cm (less what alignment absorbs).
  for (std::size_t i = 0; i < estimate.size(); i += 2) estimate[i].T_world_cam.translation().x() += 0.02;
  EXPECT_NEAR(app::evaluate_trajectory(estimate, truth).ate_rmse, 0.01, 0.002);
}

}  // namespace

namespace {

// Writes the synthetic sequence again in Replica layout and reads it back.
TEST(ReplicaDataset, ReadsJpegFramesScaledDepthAndMatrixTrajectory) {
  TempDir dir;
  write_small_sequence(dir / "tum");
  const app::Dataset tum = app::open_dataset(dir / "tum");
  std::filesystem::create_directories(dir / "replica" / "results");
  std::string traj;
  for (std::size_t i = 0; i < tum.entries.size(); ++i) {
    const splat::RgbdFrame f = tum.load(i);
    splat::Image8 rgb(f.width(), f.height(), 3);
    for (std::size_t k = 0; k < f.rgb.size(); ++k) rgb.data[k] = static_cast<uint8_t>(std::lround(f.rgb[k] * 255));
    splat::Image16 depth(f.width(), f.height(), 1);
    for (std::size_t k = 0; k < f.depth.size(); ++k) depth.data[k] = static_cast<uint16_t>(std::lround(f.depth[k] * 6553.5));
    char name[32];
    std::snprintf(name, sizeof(name), "frame%06zu.jpg", i);
    app::write_jpeg_rgb8(dir / "replica" / "results" / name, rgb);
    std::snprintf(name, sizeof(name), "depth%06zu.png", i);
    app::write_png_gray16(dir / "replica" / "results" / name, depth);
    const Eigen::Matrix4d m = tum.entries[i].T_world_cam_truth->matrix();
    for (int k = 0; k < 16; ++k) traj += std::to_string(m(k / 4, k % 4)) + (k < 15 ? " " : "\n");
  }
  gslam::test::write_text(dir / "replica" / "traj.txt", traj);
  app::DatasetOptions options;
  options.intrinsics = "52,52,32,24";  // not the Replica camera
  const app::Dataset replica = app::open_dataset(dir / "replica", options);
  EXPECT_EQ(replica.format, "replica");
  ASSERT_EQ(replica.entries.size(), 3u);
  EXPECT_NEAR(replica.entries[2].timestamp, 2.0 / 30.0, 1e-12);
  EXPECT_TRUE(replica.entries[1].T_world_cam_truth->isApprox(*tum.entries[1].T_world_cam_truth, 1e-5));
  const splat::RgbdFrame a = tum.load(1), b = replica.load(1);
  double colour_error = 0;
  for (std::size_t k = 0; k < a.rgb.size(); ++k) colour_error += std::abs(a.rgb[k] - b.rgb[k]);
  EXPECT_LT(colour_error / static_cast<double>(a.rgb.size()), 0.03) << "JPEG at quality 95 is close";
  for (std::size_t k = 0; k < a.depth.size(); ++k) ASSERT_NEAR(a.depth[k], b.depth[k], 2e-4) << "pixel " << k;

  gslam::test::write_text(dir / "replica" / "traj.txt", "1 0 0 0 0 1 0 0\n");
  GSLAM_EXPECT_ERROR(app::open_dataset(dir / "replica", options), "traj.txt", "line 1", "16 numbers");
}

}  // namespace
