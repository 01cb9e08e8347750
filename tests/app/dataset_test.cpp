#include "datasets/dataset.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "app/run_gslam.h"
#include "evaluation/trajectory_errors.h"
#include "commands/run_input.h"
#include "datasets/synthetic_sequence.h"
#include "io/image_io.h"
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

// TUM's fr1 and fr2 images are raw: their presets carry the Kinects' lens distortion, and frames
// load undistorted into a pinhole camera; fr3's are rectified (see RealSequence... above).
TEST(TumDataset, Fr1AndFr2PresetsUndistortTheirKinectsLens) {
  TempDir dir;
  for (const char* camera : {"freiburg1", "freiburg2"}) {
    // Two 640x480 frames (the size the calibration is for), a plain grey room 2 m away.
    const std::filesystem::path seq = dir / (std::string("rgbd_dataset_") + camera + "_desk");
    std::filesystem::create_directories(seq / "rgb");
    std::filesystem::create_directories(seq / "depth");
    splat::Image16 depth(640, 480, 1);
    std::fill(depth.data.begin(), depth.data.end(), uint16_t{10000});
    for (const char* stamp : {"1.000000", "1.033333"}) {
      app::write_png_rgb(seq / "rgb" / (std::string(stamp) + ".png"), 640, 480,
                         std::vector<float>(640 * 480 * 3, 0.5f));
      app::write_png_gray16(seq / "depth" / (std::string(stamp) + ".png"), depth);
    }
    gslam::test::write_text(seq / "rgb.txt",
                            "1.000000 rgb/1.000000.png\n1.033333 rgb/1.033333.png\n");
    gslam::test::write_text(seq / "depth.txt",
                            "1.000000 depth/1.000000.png\n1.033333 depth/1.033333.png\n");
    const app::Dataset d = app::open_dataset(seq);
    EXPECT_DOUBLE_EQ(d.distortion.k1, camera[8] == '1' ? 0.262383 : 0.231222) << camera;
    ASSERT_TRUE(d.undistortion) << camera;
    EXPECT_DOUBLE_EQ(d.undistortion->raw_camera().fx, camera[8] == '1' ? 517.306408 : 520.908620);
    EXPECT_DOUBLE_EQ(d.intrinsics.fx, d.undistortion->camera().fx);
    const splat::RgbdFrame f = d.load(1);
    EXPECT_DOUBLE_EQ(f.camera.fx, d.intrinsics.fx) << "frames come in the pinhole camera";
    EXPECT_DOUBLE_EQ(f.camera.cy, d.intrinsics.cy);
    EXPECT_TRUE(std::all_of(f.depth.begin(), f.depth.end(), [](float z) { return z == 2.0f; }))
        << "every pixel of the pinhole view has the raw view's depth";
    // Given intrinsics replace the preset, distortion included.
    app::DatasetOptions options;
    options.intrinsics = "500,500,320,240";
    const app::Dataset given = app::open_dataset(seq, options);
    EXPECT_FALSE(given.distortion.any());
    EXPECT_FALSE(given.undistortion);
    EXPECT_DOUBLE_EQ(given.intrinsics.fx, 500);
  }
}

// intrinsics.txt and --intrinsics may follow the camera with its distortion; a run records the
// raw camera and the distortion, so that eval and --resume undistort the frames alike.
TEST(Dataset, IntrinsicsMayStateTheLensDistortionAndRunsRecordIt) {
  TempDir dir;
  write_small_sequence(dir / "seq");
  gslam::test::write_text(dir / "seq" / "intrinsics.txt",
                          "52 52 32 24 0.1 -0.2 0.001 0.002 0.05\n");
  const app::Dataset d = app::open_dataset(dir / "seq");
  EXPECT_EQ(d.distortion.coefficients(), (std::vector<double>{0.1, -0.2, 0.001, 0.002, 0.05}));
  ASSERT_TRUE(d.undistortion);
  EXPECT_NE(d.intrinsics.fx, 52) << "the pinhole camera of the undistorted frames";

  const app::RecordedInput recorded = app::recorded_input(
      app::run_input_json(dir / "seq", d, 0, 0, app::SlamConfig{}), "summary.json");
  const app::Dataset again = app::open_dataset(dir / "seq", recorded.options);
  EXPECT_EQ(again.distortion.coefficients(), d.distortion.coefficients());
  EXPECT_DOUBLE_EQ(again.intrinsics.fx, d.intrinsics.fx);
  EXPECT_DOUBLE_EQ(again.intrinsics.cx, d.intrinsics.cx);

  app::DatasetOptions options;
  options.intrinsics = "52,52,32,24,0.1,-0.2,0.001,0.002";
  EXPECT_DOUBLE_EQ(app::open_dataset(dir / "seq", options).distortion.p2, 0.002)
      << "k3 may be left out";
  options.intrinsics = "52,52,32,24,0.1,-0.2";
  GSLAM_EXPECT_ERROR(app::open_dataset(dir / "seq", options), "intrinsics '52,52,32,24,0.1,-0.2'",
                     "k1,k2,p1,p2[,k3]");
  gslam::test::write_text(dir / "seq" / "intrinsics.txt", "52 52 32 24 0.1 -0.2\n");
  GSLAM_EXPECT_ERROR(app::open_dataset(dir / "seq"), "intrinsics.txt", "'k1 k2 p1 p2 [k3]'");
  gslam::test::write_text(dir / "seq" / "intrinsics.txt", "52 52 32 24 0.1 -0.2 0 0 1e300\n");
  GSLAM_EXPECT_ERROR(app::open_dataset(dir / "seq"), "intrinsics.txt", "distortion k3 is 1e+300",
                     "under 100");
  // The distortion may follow on a line of its own.
  gslam::test::write_text(dir / "seq" / "intrinsics.txt",
                          "52 52 32 24\n0.1 -0.2 0.001 0.002 0.05\n");
  EXPECT_DOUBLE_EQ(app::open_dataset(dir / "seq").distortion.k3, 0.05);
  gslam::test::write_text(dir / "seq" / "intrinsics.txt",
                          "52 52 32 24" + std::string(5000, ' ') + "\n");
  GSLAM_EXPECT_ERROR(app::open_dataset(dir / "seq"), "intrinsics.txt", "over 4 KiB");
  // A lens that folds the image over (k1 -3 turns back at a third of the focal length).
  gslam::test::write_text(dir / "seq" / "intrinsics.txt", "52 52 32 24 -3 0 0 0\n");
  GSLAM_EXPECT_ERROR(app::open_dataset(dir / "seq"), "intrinsics.txt",
                     "folds the 64x48 image over");
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
      "rgb/NAME.png|jpg + depth/NAME.png",
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
  expect_error(dir / "pngs", "has 2 image files but no rgb/ and depth/ holding them, nor rgb.txt "
                             "and depth.txt listing them");
  std::filesystem::create_directories(dir / "folders" / "rgb");
  expect_error(dir / "folders", "has rgb/ but no depth/");
  std::filesystem::create_directories(dir / "folders" / "depth");
  expect_error(dir / "folders", "has rgb/ and depth/ but no .png or .jpg image in rgb/");
  gslam::test::write_text(dir / "folders" / "rgb" / "1.0.png", "");
  expect_error(dir / "folders", "has rgb/ and depth/ but no .png image in depth/");
  std::filesystem::create_directories(dir / "replica" / "results");
  expect_error(dir / "replica", "has results/ but no traj.txt");
  gslam::test::write_text(dir / "other" / "notes.md", "");
  expect_error(dir / "other", "has none of rgb.txt, depth.txt, rgb/, depth/, traj.txt, results/");
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

namespace {

// The small synthetic sequence at DIR/tum and a copy at DIR/images without rgb.txt and depth.txt.
void write_tum_and_images(const TempDir& dir) {
  write_small_sequence(dir / "tum");
  std::filesystem::copy(dir / "tum", dir / "images", std::filesystem::copy_options::recursive);
  std::filesystem::remove(dir / "images" / "rgb.txt");
  std::filesystem::remove(dir / "images" / "depth.txt");
}

// An 8x6 colour image and depth image at DIR/rgb/NAME and DIR/depth/DEPTH_NAME (none if empty).
void write_pair(const std::filesystem::path& dir, const std::string& name,
                const std::string& depth_name) {
  std::filesystem::create_directories(dir / "rgb");
  std::filesystem::create_directories(dir / "depth");
  splat::Image8 rgb(8, 6, 3);
  for (std::size_t k = 0; k < rgb.data.size(); ++k) rgb.data[k] = static_cast<uint8_t>(k);
  if (name.ends_with(".jpg")) {
    app::write_jpeg_rgb8(dir / "rgb" / name, rgb);
  } else {
    app::write_png_rgb8(dir / "rgb" / name, rgb);
  }
  splat::Image16 depth(8, 6, 1);
  for (auto& z : depth.data) z = 5000;
  if (!depth_name.empty()) app::write_png_gray16(dir / "depth" / depth_name, depth);
}

std::vector<double> timestamps(const app::Dataset& d) {
  std::vector<double> out;
  for (const auto& e : d.entries) out.push_back(e.timestamp);
  return out;
}

std::vector<std::string> colour_names(const app::Dataset& d) {
  std::vector<std::string> out;
  for (const auto& e : d.entries) out.push_back(e.rgb.filename().string());
  return out;
}

TEST(ImagesDataset, TumSequenceWithoutListsReadsTheSameFrames) {
  TempDir dir;
  write_tum_and_images(dir);
  const app::Dataset tum = app::open_dataset(dir / "tum");
  const app::Dataset images = app::open_dataset(dir / "images");
  EXPECT_EQ(tum.format, "tum");
  EXPECT_EQ(images.format, "images");
  EXPECT_TRUE(images.warnings.empty()) << images.warnings.front();
  EXPECT_EQ(images.frames_used(), "3 frames");
  EXPECT_DOUBLE_EQ(images.depth_scale, 5000);
  EXPECT_DOUBLE_EQ(images.intrinsics.fx, tum.intrinsics.fx);
  EXPECT_DOUBLE_EQ(images.intrinsics.fy, tum.intrinsics.fy);
  EXPECT_DOUBLE_EQ(images.intrinsics.cx, tum.intrinsics.cx);
  EXPECT_DOUBLE_EQ(images.intrinsics.cy, tum.intrinsics.cy);
  EXPECT_EQ(images.intrinsics.width, tum.intrinsics.width);
  EXPECT_EQ(images.intrinsics.height, tum.intrinsics.height);
  ASSERT_EQ(images.entries.size(), tum.entries.size());
  for (std::size_t i = 0; i < tum.entries.size(); ++i) {
    const app::DatasetEntry &a = tum.entries[i], &b = images.entries[i];
    EXPECT_DOUBLE_EQ(b.timestamp, a.timestamp) << "frame " << i;
    EXPECT_EQ(b.rgb.filename(), a.rgb.filename()) << "frame " << i;
    EXPECT_EQ(b.depth.filename(), a.depth.filename()) << "frame " << i;
    ASSERT_TRUE(a.T_world_cam_truth && b.T_world_cam_truth) << "frame " << i;
    EXPECT_TRUE(b.T_world_cam_truth->isApprox(*a.T_world_cam_truth, 1e-12)) << "frame " << i;
  }
  const splat::RgbdFrame f = images.load(2), g = tum.load(2);
  EXPECT_EQ(f.rgb, g.rgb);
  EXPECT_EQ(f.depth, g.depth);
  // --intrinsics, --depth-scale and --max-frames apply as to every layout.
  app::DatasetOptions options;
  options.intrinsics = "40,41,30,20";
  options.depth_scale = 1000;
  options.max_frames = 2;
  const app::Dataset custom = app::open_dataset(dir / "images", options);
  EXPECT_DOUBLE_EQ(custom.intrinsics.fy, 41);
  EXPECT_DOUBLE_EQ(custom.depth_scale, 1000);
  EXPECT_EQ(custom.frames_used(), "2 frames used (of 3 listed; 1 beyond --max-frames)");
}

TEST(ImagesDataset, NumericNamesSortAsNumbersOthersByNameAtThirtyHertz) {
  TempDir dir;
  for (const std::string stem : {"10.0", "1.5", "2"}) {
    write_pair(dir / "numbers", stem + ".png", stem + ".png");
  }
  gslam::test::write_text(dir / "numbers" / "intrinsics.txt", "10 10 4 3\n");
  const app::Dataset numbers = app::open_dataset(dir / "numbers");
  EXPECT_EQ(numbers.format, "images");
  EXPECT_EQ(colour_names(numbers), (std::vector<std::string>{"1.5.png", "2.png", "10.0.png"}));
  EXPECT_EQ(timestamps(numbers), (std::vector<double>{1.5, 2.0, 10.0}));
  EXPECT_EQ(numbers.intrinsics.width, 8);

  // One name that is not a number: every frame in name order, stamped index / 30 s. Colour may be
  // JPEG; depth is paired by the stem.
  write_pair(dir / "names", "c10.png", "c10.png");
  write_pair(dir / "names", "a.jpg", "a.png");
  write_pair(dir / "names", "c9.png", "c9.png");
  write_pair(dir / "names", "5.png", "5.png");
  gslam::test::write_text(dir / "names" / "intrinsics.txt", "10 10 4 3\n");
  const app::Dataset names = app::open_dataset(dir / "names");
  EXPECT_EQ(colour_names(names), (std::vector<std::string>{"5.png", "a.jpg", "c10.png", "c9.png"}));
  const std::vector<double> t = timestamps(names);
  ASSERT_EQ(t.size(), 4u);
  for (std::size_t i = 0; i < t.size(); ++i) EXPECT_DOUBLE_EQ(t[i], static_cast<double>(i) / 30.0) << "frame " << i;
  EXPECT_EQ(names.load(1).width(), 8);
}

TEST(ImagesDataset, ColourWithoutDepthIsCountedAndWarnedOnlyWhenMost) {
  TempDir dir;
  write_tum_and_images(dir);
  std::filesystem::remove(std::filesystem::directory_iterator(dir / "images" / "depth")->path());
  const app::Dataset one = app::open_dataset(dir / "images");
  EXPECT_EQ(one.listed, 3u);
  EXPECT_EQ(one.unmatched, 1u);
  EXPECT_EQ(one.entries.size(), 2u);
  EXPECT_EQ(one.frames_used(), "2 frames used (of 3 listed; 1 no depth image)");
  EXPECT_TRUE(one.warnings.empty()) << one.warnings.front();
  std::filesystem::remove(std::filesystem::directory_iterator(dir / "images" / "depth")->path());
  const app::Dataset most = app::open_dataset(dir / "images");
  EXPECT_EQ(most.unmatched, 2u);
  ASSERT_EQ(most.warnings.size(), 1u);
  EXPECT_NE(most.warnings[0].find("2 of 3 colour images in rgb/ have no depth image of the same name"),
            std::string::npos)
      << most.warnings[0];
}

TEST(ImagesDataset, MissingIntrinsicsIsAOneLineErrorNamingTheFile) {
  TempDir dir;
  write_tum_and_images(dir);
  std::filesystem::remove(dir / "images" / "intrinsics.txt");
  GSLAM_EXPECT_ERROR(app::open_dataset(dir / "images"), "intrinsics.txt: not found", "'fx fy cx cy'",
                     "--intrinsics fx,fy,cx,cy");
  try {
    app::open_dataset(dir / "images");
    ADD_FAILURE() << "no error without intrinsics.txt";
  } catch (const splat::Error& e) {
    EXPECT_EQ(std::string(e.what()).find('\n'), std::string::npos) << e.what();
  }
  app::DatasetOptions options;
  options.intrinsics = "52,52,32,24";
  EXPECT_EQ(app::open_dataset(dir / "images", options).entries.size(), 3u);
  // Two colour images with one stem: the pairing would be ambiguous.
  write_pair(dir / "images", "1000.000000.jpg", "");
  GSLAM_EXPECT_ERROR(app::open_dataset(dir / "images", options), "1000.000000.jpg",
                     "have the same name stem");
}

// gslam reconstruct on a folder of images; gslam eval of a live --watch run on the same folder.
TEST(CliImages, ReconstructsAFolderOfImagesAndEvaluatesAWatchedRun) {
  TempDir dir;
  app::SyntheticOptions o;
  o.frames = 4;
  app::write_synthetic_sequence(dir / "seq", o);
  std::filesystem::remove(dir / "seq" / "rgb.txt");
  std::filesystem::remove(dir / "seq" / "depth.txt");
  gslam::test::write_text(dir / "quick.json", R"({"refine_passes": 0, "mapping": {"iterations": 3}})");
  const auto r = run_gslam("reconstruct " + (dir / "seq").string() + " --out " + (dir / "run").string() +
                           " --config " + (dir / "quick.json").string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("(images)"), std::string::npos) << r.output;

  std::ofstream(dir / "seq" / "END") << "\n";
  // Every frame, whatever the machine's load: the folder is complete, and a watched stream keeps
  // only the newest frame while tracking is busy.
  const auto live = run_gslam("live " + (dir / "seq").string() + " --watch --every-frame --headless --out " +
                              (dir / "live").string() + " --config " + (dir / "quick.json").string());
  ASSERT_EQ(live.exit_code, 0) << live.output;
  const auto eval = run_gslam("eval " + (dir / "live").string());
  EXPECT_EQ(eval.exit_code, 0) << eval.output;
  EXPECT_NE(eval.output.find("ATE RMSE"), std::string::npos) << eval.output;
}

}  // namespace
