// ROS recordings as input (datasets/bag_dataset.h): an MCAP file written by the MCAP project's
// reference writer (tests/interop/write_mcap.mjs) and a ROS 1 bag written with rosbag hold the
// first teddy frames; both open to the folder's frames bit for bit, with the camera from
// CameraInfo, and reconstruct to the folder's trajectory. Bad recordings give one-line errors.
// Without Node and the npm packages, or without ROS, the tests skip, unless
// GSLAM_REQUIRE_ROS_TESTS (CI) makes that a failure.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <nlohmann/json.hpp>
#include <sstream>

#include "app/run_gslam.h"
#include "datasets/bag_reader.h"
#include "datasets/dataset.h"
#include "datasets/mcap_reader.h"
#include "io/image_io.h"
#include "io/trajectory.h"
#include "support/expect_error.h"
#include "support/run_command.h"
#include "support/require_tool.h"
#include "support/temp_dir.h"
#include "support/teddy_recording.h"
#include "support/test_data.h"
#ifdef GSLAM_HAVE_ROS1
#include "support/ros1_bag_writer.h"
#endif

namespace {

using gslam::test::colour_bytes;
using gslam::test::float_bytes;
using gslam::test::kMountQ;
using gslam::test::kMountT;
using gslam::test::kTeddyFolder;
using gslam::test::kTeddyK;
using gslam::test::mocap;
using gslam::test::open_teddy;
using gslam::test::ros_time;
using gslam::test::TempDir;
using gslam::test::Transform;
// Frames in the recordings: enough for the trajectory comparison, few for the test time.
constexpr int kFrames = 20;
// Bag and folder runs read the same floats, so their trajectories agree to rounding; the issue's
// target is 0.1 mm.
constexpr double kTrajectoryTolerance = 1e-4;

std::string mcap_writer_missing() {
  const std::filesystem::path tools = GSLAM_TOOLS_DIR;
  if (!gslam::test::program_available("node"))
    return "node is not on PATH (scripts/install_deps.sh installs it)";
  if (!gslam::test::program_available("lz4"))
    return "the lz4 command is missing (apt-get install lz4)";
  for (const char* p : {"@mcap/core", "@foxglove/rosmsg2-serialization", "@foxglove/rosmsg",
                        "@foxglove/wasm-zstd"}) {
    if (!std::filesystem::exists(tools / "node_modules" / p)) {
      return std::string(p) + " is not under " + tools.string() +
             "/node_modules (scripts/install_deps.sh installs it)";
    }
  }
  return "";
}



// With --gt-frames world,rgb_optical: the folder's ground truth (groundtruth.txt) times the mount.
void expect_tf_ground_truth(const app::Dataset& folder, const std::filesystem::path& recording,
                            int frames) {
  app::DatasetOptions o;
  o.gt_frames = "world,rgb_optical";
  const app::Dataset bag = app::open_dataset(recording, o);
  Eigen::Isometry3d mount = Eigen::Isometry3d::Identity();
  mount.linear() =
      Eigen::Quaterniond(kMountQ[3], kMountQ[0], kMountQ[1], kMountQ[2]).toRotationMatrix();
  mount.translation() = Eigen::Vector3d(kMountT[0], kMountT[1], kMountT[2]);
  int compared = 0;
  for (int i = 0; i < frames; ++i) {
    const auto& truth = folder.entries[std::size_t(i)].T_world_cam_truth;
    const auto& from_tf = bag.entries[std::size_t(i)].T_world_cam_truth;
    ASSERT_EQ(from_tf.has_value(), truth.has_value()) << "frame " << i;
    if (!truth) continue;
    EXPECT_TRUE(from_tf->isApprox(*truth * mount, 1e-9)) << "frame " << i << "\n"
                                                         << from_tf->matrix() << "\n"
                                                         << (*truth * mount).matrix();
    ++compared;
  }
  EXPECT_GT(compared, frames / 2);
  o.gt_frames = "world,nowhere";
  GSLAM_EXPECT_ERROR(app::open_dataset(recording, o),
                     "--gt-frames world,nowhere: no chain of transforms from world to nowhere",
                     "world -> kinect", "kinect -> rgb_optical");
}


// Depth as 16UC1: the PNG's stored values.
std::vector<std::uint8_t> png_bytes(const std::filesystem::path& png) {
  const splat::Image16 d = app::read_png_gray16(png);
  std::vector<std::uint8_t> out(d.data.size() * 2);
  std::memcpy(out.data(), d.data.data(), out.size());
  return out;
}

void write_bytes(const std::filesystem::path& path, const std::vector<std::uint8_t>& bytes) {
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
}

struct McapSpec {
  std::string compression = "zstd";
  std::string colour_encoding = "bgr8";  // or "png": sensor_msgs/CompressedImage
  std::string depth_encoding = "32FC1";  // or 16UC1 (the PNG's values)
  bool depth = true, camera_info = true;
  bool tf = false;     // mocap() on /tf and the mount on /tf_static
  bool chunks = true;  // false: messages at the top level of the file
  int frames = kFrames;
  std::vector<double> distortion = {0, 0, 0, 0, 0};  // CameraInfo's plumb_bob d
  std::string colour_topic = "/camera/rgb/image_color";
  std::array<double, 12> p{};                 // CameraInfo's P; zeros: from K
  std::array<int, 2> info_size = {640, 480};  // CameraInfo's width and height
};

// Writes the first spec.frames teddy frames with the reference writer to `out`.
void write_teddy_mcap(const app::Dataset& folder, const McapSpec& spec,
                      const std::filesystem::path& out) {
  const std::filesystem::path raw = out.parent_path() / (out.stem().string() + "_raw");
  std::filesystem::create_directories(raw);
  std::ostringstream frames;
  for (int i = 0; i < spec.frames; ++i) {
    const app::DatasetEntry& e = folder.entries[std::size_t(i)];
    const splat::RgbdFrame f = folder.load(std::size_t(i));
    const std::string c = std::to_string(i) + ".colour", d = std::to_string(i) + ".depth";
    if (spec.colour_encoding == "png") {  // a CompressedImage holding the folder's PNG file
      std::filesystem::copy_file(e.rgb, raw / c);
    } else {
      write_bytes(raw / c, colour_bytes(f, spec.colour_encoding == "bgr8"));
    }
    write_bytes(raw / d,
                spec.depth_encoding == "32FC1" ? float_bytes(f.depth) : png_bytes(e.depth));
    const auto ct = ros_time(e.rgb), dt = ros_time(e.depth);
    frames << (i ? "," : "") << R"({"colour": ")" << c << R"(", "colour_stamp": [)" << ct[0] << ","
           << ct[1] << R"(], "depth": ")" << d << R"(", "depth_stamp": [)" << dt[0] << "," << dt[1]
           << "]}";
  }
  // The CameraInfo: "k", "d", optionally "p", and the size it states.
  std::ostringstream camera;
  camera << std::setprecision(17);
  const auto list = [&](const char* name, const auto& values) {
    camera << '"' << name << R"(": [)";
    for (std::size_t i = 0; i < values.size(); ++i) camera << (i ? "," : "") << values[i];
    camera << "], ";
  };
  list("k", kTeddyK);
  list("d", spec.distortion);
  if (spec.p[0] > 0) list("p", spec.p);
  camera << R"("info_width": )" << spec.info_size[0] << R"(, "info_height": )" << spec.info_size[1];
  std::ostringstream tf;
  tf << std::setprecision(17);
  if (spec.tf) {
    const auto json = [&](const std::array<std::uint32_t, 2>& stamp, const char* parent,
                          const char* child, const std::array<double, 3>& t,
                          const std::array<double, 4>& q) {
      tf << R"({"stamp": [)" << stamp[0] << "," << stamp[1] << R"(], "parent": ")" << parent
         << R"(", "child": ")" << child << R"(", "t": [)" << t[0] << "," << t[1] << "," << t[2]
         << R"(], "q": [)" << q[0] << "," << q[1] << "," << q[2] << "," << q[3] << "]}";
    };
    tf << R"(, "tf": [)";
    const std::vector<Transform> poses = mocap(folder, 0, spec.frames);
    for (std::size_t i = 0; i < poses.size(); ++i) {
      if (i) tf << ",";
      json(poses[i].stamp, "/world", "/kinect", poses[i].t, poses[i].q);
    }
    tf << R"(], "tf_static": [)";
    json(ros_time(folder.entries.front().rgb), "kinect", "rgb_optical", kMountT, kMountQ);
    tf << "]";
  }
  gslam::test::write_text(
      raw / "manifest.json",
      R"({"compression": ")" + spec.compression + R"(", "chunk_size": 1500000, "use_chunks": )" +
          (spec.chunks ? "true" : "false") + R"(, "width": 640, "height": 480, )" + camera.str() +
          R"(, "colour_topic": ")" + spec.colour_topic + R"(", "colour_encoding": ")" +
          spec.colour_encoding + R"(", "depth_topic": )" +
          (spec.depth ? R"("/camera/depth/image")" : "null") + R"(, "depth_encoding": ")" +
          spec.depth_encoding + R"(", "info_topic": )" +
          (spec.camera_info ? R"("/camera/rgb/camera_info")" : "null") + R"(, "frames": [)" +
          frames.str() + "]" + tf.str() + "}");
  const auto r = gslam::test::run_command("node " + std::string(GSLAM_SOURCE_DIR) +
                                          "/tests/interop/write_mcap.mjs " + GSLAM_TOOLS_DIR + " " +
                                          (raw / "manifest.json").string() + " " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::filesystem::remove_all(raw);
}

// Frames, stamps, camera and ground truth of `bag` equal the folder's.
void expect_same_frames(const app::Dataset& folder, const app::Dataset& bag, int frames) {
  ASSERT_EQ(bag.entries.size(), std::size_t(frames));
  EXPECT_EQ(bag.intrinsics.width, 640);
  EXPECT_EQ(bag.intrinsics.height, 480);
  for (int i = 0; i < frames; ++i) {
    const auto& fe = folder.entries[std::size_t(i)];
    const auto& be = bag.entries[std::size_t(i)];
    EXPECT_NEAR(be.timestamp, fe.timestamp, 1e-6) << "frame " << i;
    ASSERT_EQ(be.T_world_cam_truth.has_value(), fe.T_world_cam_truth.has_value()) << "frame " << i;
    if (fe.T_world_cam_truth) {
      EXPECT_TRUE(be.T_world_cam_truth->isApprox(*fe.T_world_cam_truth, 1e-12)) << "frame " << i;
    }
    const splat::RgbdFrame a = folder.load(std::size_t(i)), b = bag.load(std::size_t(i));
    ASSERT_EQ(a.rgb.size(), b.rgb.size()) << "frame " << i;
    ASSERT_EQ(a.depth.size(), b.depth.size()) << "frame " << i;
    EXPECT_EQ(std::memcmp(a.rgb.data(), b.rgb.data(), a.rgb.size() * 4), 0)
        << "colour of frame " << i;
    EXPECT_EQ(std::memcmp(a.depth.data(), b.depth.data(), a.depth.size() * 4), 0)
        << "depth of frame " << i;
  }
}

// Largest distance between the positions of two runs' trajectories, line by line.
double trajectory_difference(const std::filesystem::path& a, const std::filesystem::path& b) {
  const auto ta = app::read_tum_trajectory(a), tb = app::read_tum_trajectory(b);
  EXPECT_EQ(ta.size(), tb.size());
  double worst = 0;
  for (std::size_t i = 0; i < std::min(ta.size(), tb.size()); ++i) {
    EXPECT_NEAR(ta[i].timestamp, tb[i].timestamp, 1e-6) << "line " << i;
    worst =
        std::max(worst, (ta[i].T_world_cam.translation() - tb[i].T_world_cam.translation()).norm());
  }
  return worst;
}

// Reconstructs the folder and the recording (kFrames frames; 10 in sanitized builds, which run
// some 20x slower) and compares their trajectories; evaluates the recording's run, ground truth
// coming from /tf (--gt-frames, recorded in the run's summary.json with the topics, so that eval
// needs no options).
void expect_same_reconstruction(const std::filesystem::path& recording, const TempDir& dir) {
  gslam::test::write_text(dir / "quick.json",
                          R"({"refine_passes": 0, "mapping": {"iterations": 3}})");
  const int frames = gslam::test::test_time_scale() > 1 ? 10 : kFrames;
  const std::string common = " --max-frames " + std::to_string(frames) +
                             " --backend cpu --config " + (dir / "quick.json").string();
  const auto folder = run_gslam("reconstruct " + gslam::test::shared_data(kTeddyFolder).string() +
                                " --out " + (dir / "folder_run").string() + common);
  ASSERT_EQ(folder.exit_code, 0) << folder.output;
  const auto bag =
      run_gslam("reconstruct " + recording.string() + " --out " + (dir / "bag_run").string() +
                common + " --color-topic /camera/rgb/image_color --gt-frames world,kinect");
  ASSERT_EQ(bag.exit_code, 0) << bag.output;
  const nlohmann::json input =
      nlohmann::json::parse(gslam::test::read_text(dir / "bag_run" / "summary.json"))["input"];
  EXPECT_EQ(input.value("color_topic", ""), "/camera/rgb/image_color") << input.dump();
  EXPECT_EQ(input.value("depth_topic", ""), "/camera/depth/image") << input.dump();
  EXPECT_EQ(input.value("gt_frames", ""), "world,kinect") << input.dump();
  const double difference = trajectory_difference(dir / "folder_run" / "trajectory.txt",
                                                  dir / "bag_run" / "trajectory.txt");
  EXPECT_LT(difference, kTrajectoryTolerance) << "metres";
  std::printf("bag vs folder trajectory: largest position difference %.3g m over %d frames\n",
              difference, frames);
  const auto eval = run_gslam("eval " + (dir / "bag_run").string() + " --backend cpu --every 10");
  EXPECT_EQ(eval.exit_code, 0) << eval.output;
  EXPECT_NE(eval.output.find("ATE"), std::string::npos) << eval.output;
}

// `gslam live` replays the recording (every frame, no clock, so the test does not depend on
// the machine's speed) and writes a run that eval takes.
void expect_live_replay(const std::filesystem::path& recording, const TempDir& dir) {
  gslam::test::write_text(dir / "quick.json",
                          R"({"refine_passes": 0, "mapping": {"iterations": 3}})");
  const auto live =
      run_gslam("live " + recording.string() +
                " --headless --every-frame --max-frames 8 --backend cpu --out " +
                (dir / "live_run").string() + " --config " + (dir / "quick.json").string());
  ASSERT_EQ(live.exit_code, 0) << live.output;
  EXPECT_EQ(app::read_tum_trajectory(dir / "live_run" / "trajectory.txt").size(), 8u)
      << live.output;
  const auto eval = run_gslam("eval " + (dir / "live_run").string() + " --backend cpu --every 10");
  EXPECT_EQ(eval.exit_code, 0) << eval.output;
}

class McapInput : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string missing = mcap_writer_missing();
    GSLAM_REQUIRE_TOOL(missing.empty(), "the MCAP reference writer is unavailable: " + missing);
    if (gslam::test::shared_data(kTeddyFolder).empty())
      GTEST_SKIP() << "shared data " << kTeddyFolder << " not found";
  }
};

TEST_F(McapInput, ReferenceWriterFileGivesTheFolderFramesAndTrajectory) {
  TempDir dir;
  const app::Dataset folder = open_teddy(kFrames);
  const std::filesystem::path mcap = dir / "teddy.mcap";
  McapSpec spec;  // zstd chunks, bgr8 colour, 32FC1 depth
  spec.tf = true;
  write_teddy_mcap(folder, spec, mcap);
  std::filesystem::copy_file(gslam::test::shared_data(kTeddyFolder) / "groundtruth.txt",
                             dir / "groundtruth.txt");
  const app::Dataset bag = app::open_dataset(mcap);
  EXPECT_EQ(bag.format, "mcap");
  EXPECT_DOUBLE_EQ(bag.depth_scale, 1.0) << "32FC1 is in metres";
  // From CameraInfo: the temporary path names no freiburg camera.
  EXPECT_DOUBLE_EQ(bag.intrinsics.fx, kTeddyK[0]);
  EXPECT_DOUBLE_EQ(bag.intrinsics.fy, kTeddyK[4]);
  EXPECT_DOUBLE_EQ(bag.intrinsics.cx, kTeddyK[2]);
  EXPECT_DOUBLE_EQ(bag.intrinsics.cy, kTeddyK[5]);
  EXPECT_TRUE(bag.has_ground_truth());
  expect_same_frames(folder, bag, kFrames);
  expect_tf_ground_truth(folder, mcap, kFrames);
  expect_same_reconstruction(mcap, dir);
  expect_live_replay(mcap, dir);
}

TEST_F(McapInput, CompressedPngColourWithoutChunksDecodesAsTheFile) {
  TempDir dir;
  const app::Dataset folder = open_teddy(3);
  McapSpec spec;
  spec.colour_encoding = "png";
  spec.chunks = false;
  spec.frames = 3;
  write_teddy_mcap(folder, spec, dir / "teddy.mcap");
  expect_same_frames(folder, app::open_dataset(dir / "teddy.mcap"), 3);
}

// A CameraInfo with plumb_bob distortion: frames come undistorted into a pinhole camera, as a
// folder given the same camera and distortion gives them.
TEST_F(McapInput, CameraInfoDistortionUndistortsTheFrames) {
  TempDir dir;
  McapSpec spec;
  spec.frames = 2;
  spec.distortion = {0.262383, -0.953104, -0.005358, 0.002628, 1.163314};  // TUM's fr1 Kinect
  write_teddy_mcap(open_teddy(2), spec, dir / "lens.mcap");
  const app::Dataset bag = app::open_dataset(dir / "lens.mcap");
  EXPECT_EQ(bag.distortion.coefficients(), spec.distortion);
  ASSERT_TRUE(bag.undistortion);
  EXPECT_GT(bag.intrinsics.fx, kTeddyK[0]) << "the pinhole view inside the raw one";
  expect_same_frames(
      open_teddy(2, "535.4,539.2,320.1,247.6,0.262383,-0.953104,-0.005358,0.002628,1.163314"), bag,
      2);
}

// ROS's convention: images on a *rect* topic are already rectified, into CameraInfo's P; its D
// describes the raw images and must not be applied again. A CameraInfo of another size is
// another camera's.
TEST_F(McapInput, RectifiedTopicsTakePAndNotD) {
  TempDir dir;
  McapSpec spec;
  spec.frames = 2;
  spec.distortion = {0.262383, -0.953104, -0.005358, 0.002628, 1.163314};
  spec.colour_topic = "/camera/rgb/image_rect_color";
  spec.p = {530, 0, 321, 0, 0, 531, 246, 0, 0, 0, 1, 0};
  write_teddy_mcap(open_teddy(2), spec, dir / "rect.mcap");
  const app::Dataset bag = app::open_dataset(dir / "rect.mcap");
  EXPECT_FALSE(bag.distortion.any());
  EXPECT_FALSE(bag.undistortion);
  EXPECT_DOUBLE_EQ(bag.intrinsics.fx, 530);
  EXPECT_DOUBLE_EQ(bag.intrinsics.cy, 246);
  spec.colour_topic = "/camera/rgb/image_color";
  spec.info_size = {320, 240};
  write_teddy_mcap(open_teddy(2), spec, dir / "binned.mcap");
  GSLAM_EXPECT_ERROR(app::open_dataset(dir / "binned.mcap"),
                     "/camera/rgb/camera_info is for 320x240 images",
                     "/camera/rgb/image_color has 640x480");
}

TEST_F(McapInput, Lz4ChunksAnd16BitDepth) {
  TempDir dir;
  const app::Dataset folder = open_teddy(3);
  McapSpec spec;
  spec.compression = "lz4";
  spec.colour_encoding = "rgb8";
  spec.depth_encoding = "16UC1";  // TUM's 1/5000 m values
  spec.frames = 3;
  write_teddy_mcap(folder, spec, dir / "teddy.mcap");
  EXPECT_DOUBLE_EQ(app::open_dataset(dir / "teddy.mcap").depth_scale, 1000)
      << "16UC1 is millimetres by ROS convention";
  app::DatasetOptions o;
  o.depth_scale = 5000;
  o.color_topic = "/camera/rgb/image_color";
  o.depth_topic = "/camera/depth/image";
  expect_same_frames(folder, app::open_dataset(dir / "teddy.mcap", o), 3);
}

TEST_F(McapInput, BadRecordingsGiveOneLineErrors) {
  TempDir dir;
  const app::Dataset folder = open_teddy(2);
  McapSpec spec;
  spec.frames = 2;
  write_teddy_mcap(folder, spec, dir / "good.mcap");
  // Truncated: cut inside the data.
  const std::string bytes = gslam::test::read_text(dir / "good.mcap");
  gslam::test::write_text(dir / "cut.mcap", bytes.substr(0, bytes.size() / 2));
  GSLAM_EXPECT_ERROR(app::open_dataset(dir / "cut.mcap"), (dir / "cut.mcap").string(),
                     std::string("truncated"));
  // Named topics that are not there, or not images.
  app::DatasetOptions o;
  o.depth_topic = "/camera/depth/none";
  GSLAM_EXPECT_ERROR(app::open_dataset(dir / "good.mcap", o),
                     "--depth-topic /camera/depth/none: no such topic",
                     "/camera/depth/image (sensor_msgs/Image, 2 messages)");
  o.depth_topic = "/camera/rgb/camera_info";
  GSLAM_EXPECT_ERROR(app::open_dataset(dir / "good.mcap", o), "holds sensor_msgs/CameraInfo");
  // No depth topic at all.
  spec.depth = false;
  write_teddy_mcap(folder, spec, dir / "no_depth.mcap");
  GSLAM_EXPECT_ERROR(app::open_dataset(dir / "no_depth.mcap"), (dir / "no_depth.mcap").string(),
                     std::string("no depth topic"), std::string("16UC1"));
  // A colour encoding gslam does not read: not found by type, refused when named.
  spec.depth = true;
  spec.colour_encoding = "yuv422";
  write_teddy_mcap(folder, spec, dir / "yuv.mcap");
  GSLAM_EXPECT_ERROR(app::open_dataset(dir / "yuv.mcap"), "no colour topic");
  o = {};
  o.color_topic = "/camera/rgb/image_color";
  GSLAM_EXPECT_ERROR(app::open_dataset(dir / "yuv.mcap", o),
                     "/camera/rgb/image_color message 0: encoding 'yuv422'",
                     "not a colour encoding");
  // Without CameraInfo the camera must be given.
  spec.colour_encoding = "rgb8";
  spec.camera_info = false;
  write_teddy_mcap(folder, spec, dir / "no_info.mcap");
  GSLAM_EXPECT_ERROR(app::open_dataset(dir / "no_info.mcap"), "no sensor_msgs/CameraInfo topic",
                     "--intrinsics");
  o = {};
  o.intrinsics = "500,500,320,240";
  EXPECT_DOUBLE_EQ(app::open_dataset(dir / "no_info.mcap", o).intrinsics.fx, 500);
  // Topic options are for recordings only.
  o = {};
  o.color_topic = "/x";
  GSLAM_EXPECT_ERROR(app::open_dataset(gslam::test::shared_data(kTeddyFolder), o),
                     "--color-topic, --depth-topic and --gt-frames are for ROS recordings");
}

// Hand-made MCAP records: sizes that do not fit are refused before anything is allocated.
std::string record(std::uint8_t opcode, const std::string& content) {
  std::string out(1, char(opcode));
  const std::uint64_t n = content.size();
  out.append(reinterpret_cast<const char*>(&n), 8);
  return out + content;
}
template <typename T>
std::string le(T v) {
  return std::string(reinterpret_cast<const char*>(&v), sizeof(T));
}
const std::string kMagic("\x89MCAP0\r\n", 8);

TEST(McapReader, CraftedSizesAreRefused) {
  TempDir dir;
  const std::string header = record(0x01, le<std::uint32_t>(0) + le<std::uint32_t>(0));
  const std::string end =
      record(0x0F, le<std::uint32_t>(0)) + record(0x02, std::string(20, '\0')) + kMagic;
  // A chunk claiming 1 TiB uncompressed.
  const std::string chunk =
      record(0x06, le<std::uint64_t>(0) + le<std::uint64_t>(0) + le<std::uint64_t>(1ull << 40) +
                       le<std::uint32_t>(0) + le<std::uint32_t>(4) + "zstd" + le<std::uint64_t>(0));
  gslam::test::write_text(dir / "huge.mcap", kMagic + header + chunk + end);
  GSLAM_EXPECT_ERROR(app::open_mcap(dir / "huge.mcap"), "huge.mcap: record at byte",
                     "1099511627776 bytes uncompressed");
  // A record longer than the file.
  gslam::test::write_text(dir / "long.mcap", kMagic + header + record(0x05, "xx").substr(0, 1) +
                                                 le<std::uint64_t>(1ull << 62) + end);
  GSLAM_EXPECT_ERROR(app::open_mcap(dir / "long.mcap"), "long.mcap: record at byte",
                     "runs past the end of the file");
  // A message before its channel, and a chunk compression nobody knows.
  const std::string message = record(0x05, le<std::uint16_t>(7) + le<std::uint32_t>(0) +
                                               le<std::uint64_t>(0) + le<std::uint64_t>(0));
  gslam::test::write_text(dir / "orphan.mcap", kMagic + header + message + end);
  GSLAM_EXPECT_ERROR(app::open_mcap(dir / "orphan.mcap"),
                     "message on channel 7, not defined before it");
  const std::string brotli = record(
      0x06, le<std::uint64_t>(0) + le<std::uint64_t>(0) + le<std::uint64_t>(0) +
                le<std::uint32_t>(0) + le<std::uint32_t>(6) + "brotli" + le<std::uint64_t>(0));
  gslam::test::write_text(dir / "brotli.mcap", kMagic + header + brotli + end);
  GSLAM_EXPECT_ERROR(app::open_mcap(dir / "brotli.mcap"), "chunk compression 'brotli'");
  gslam::test::write_text(dir / "not.mcap", "hello, this is not MCAP at all");
  GSLAM_EXPECT_ERROR(app::open_dataset(dir / "not.mcap"), "not.mcap: not an MCAP file");
  GSLAM_EXPECT_ERROR(app::open_dataset(dir / "absent.mcap"),
                     "absent.mcap: recording does not exist");
}

class Ros1BagInput : public ::testing::Test {
 protected:
  void SetUp() override {
#ifndef GSLAM_HAVE_ROS1
    GSLAM_REQUIRE_TOOL(
        false, "gslam was built without ROS 1 (scripts/install_deps.sh installs librosbag-dev)");
#endif
    if (gslam::test::shared_data(kTeddyFolder).empty())
      GTEST_SKIP() << "shared data " << kTeddyFolder << " not found";
  }
};

TEST_F(Ros1BagInput, RosbagFileGivesTheFolderFramesAndTrajectory) {
#ifdef GSLAM_HAVE_ROS1
  TempDir dir;
  const app::Dataset folder = open_teddy(kFrames);
  gslam::test::write_teddy_bag(folder, 0, kFrames, dir / "teddy.bag");
  std::filesystem::copy_file(gslam::test::shared_data(kTeddyFolder) / "groundtruth.txt",
                             dir / "groundtruth.txt");
  const app::Dataset bag = app::open_dataset(dir / "teddy.bag");
  EXPECT_EQ(bag.format, "rosbag");
  EXPECT_DOUBLE_EQ(bag.intrinsics.fx, kTeddyK[0]);
  EXPECT_DOUBLE_EQ(bag.intrinsics.cy, kTeddyK[5]);
  expect_same_frames(folder, bag, kFrames);
  expect_tf_ground_truth(folder, dir / "teddy.bag", kFrames);
  expect_same_reconstruction(dir / "teddy.bag", dir);
#endif
}

// A camera's usual topics: colour beside grey (colour is taken), depth in metres beside raw
// millimetres (ambiguous: named with --depth-topic).
TEST_F(Ros1BagInput, TopicsFoundByTypeOrNamed) {
#ifdef GSLAM_HAVE_ROS1
  TempDir dir;
  const app::Dataset folder = open_teddy(2);
  {
    gslam::test::Ros1BagWriter bag((dir / "camera.bag").string());
    for (int i = 0; i < 2; ++i) {
      const app::DatasetEntry& e = folder.entries[std::size_t(i)];
      const splat::RgbdFrame f = folder.load(std::size_t(i));
      const auto ct = ros_time(e.rgb), dt = ros_time(e.depth);
      if (i == 0) bag.camera_info("/camera/rgb/camera_info", ct[0], ct[1], 640, 480, kTeddyK);
      bag.image("/camera/rgb/image_color", ct[0], ct[1], "rgb8", 640, 480, 640 * 3,
                colour_bytes(f, false));
      bag.image("/camera/rgb/image_mono", ct[0], ct[1], "mono8", 640, 480, 640,
                std::vector<std::uint8_t>(640 * 480));
      bag.image("/camera/depth/image", dt[0], dt[1], "32FC1", 640, 480, 640 * 4,
                float_bytes(f.depth));
      bag.image("/camera/depth/image_raw", dt[0], dt[1], "16UC1", 640, 480, 640 * 2,
                png_bytes(e.depth));
    }
    bag.close();
  }
  GSLAM_EXPECT_ERROR(
      app::open_dataset(dir / "camera.bag"),
      "several depth topics (/camera/depth/image, /camera/depth/image_raw): choose one "
      "with --depth-topic");
  app::DatasetOptions o;
  o.depth_topic = "/camera/depth/image_raw";
  o.depth_scale = 5000;
  const app::Dataset d = app::open_dataset(dir / "camera.bag", o);
  EXPECT_EQ(d.color_topic, "/camera/rgb/image_color");
  expect_same_frames(folder, d, 2);
#endif
}

TEST_F(Ros1BagInput, CameraInfoDistortionUndistortsTheFrames) {
#ifdef GSLAM_HAVE_ROS1
  TempDir dir;
  const app::Dataset folder = open_teddy(1);
  const std::vector<double> fr1 = {0.262383, -0.953104, -0.005358, 0.002628, 1.163314};
  {
    gslam::test::Ros1BagWriter bag((dir / "lens.bag").string());
    const app::DatasetEntry& e = folder.entries.front();
    const splat::RgbdFrame f = folder.load(0);
    const auto ct = ros_time(e.rgb), dt = ros_time(e.depth);
    bag.camera_info("/camera/rgb/camera_info", ct[0], ct[1], 640, 480, kTeddyK, fr1);
    bag.image("/camera/rgb/image_color", ct[0], ct[1], "rgb8", 640, 480, 640 * 3,
              colour_bytes(f, false));
    bag.image("/camera/depth/image", dt[0], dt[1], "32FC1", 640, 480, 640 * 4,
              float_bytes(f.depth));
    bag.close();
  }
  const app::Dataset bag = app::open_dataset(dir / "lens.bag");
  EXPECT_EQ(bag.distortion.coefficients(), fr1);
  expect_same_frames(
      open_teddy(1, "535.4,539.2,320.1,247.6,0.262383,-0.953104,-0.005358,0.002628,1.163314"), bag,
      1);
#endif
}

TEST_F(Ros1BagInput, TruncatedOrUnindexedBagIsOneLineError) {
#ifdef GSLAM_HAVE_ROS1
  TempDir dir;
  gslam::test::write_teddy_bag(open_teddy(2), 0, 2, dir / "good.bag");
  const std::string bytes = gslam::test::read_text(dir / "good.bag");
  gslam::test::write_text(dir / "cut.bag", bytes.substr(0, bytes.size() / 2));
  GSLAM_EXPECT_ERROR(app::open_dataset(dir / "cut.bag"), (dir / "cut.bag").string() + ": ",
                     std::string("truncated"));
  // A bag whose recorder never wrote the index (index_pos 0, as while recording).
  std::string unindexed = bytes;
  const auto at = unindexed.find("index_pos=");
  ASSERT_NE(at, std::string::npos);
  unindexed.replace(at + 10, 8, std::string(8, '\0'));
  gslam::test::write_text(dir / "unindexed.bag", unindexed);
  GSLAM_EXPECT_ERROR(app::open_dataset(dir / "unindexed.bag"),
                     (dir / "unindexed.bag").string() + ": ", std::string("unindexed ROS 1 bag"),
                     std::string("rosbag reindex"));
  gslam::test::write_text(dir / "not.bag", "#ROSBAG V2.0\nnothing else");
  GSLAM_EXPECT_ERROR(app::open_dataset(dir / "not.bag"), (dir / "not.bag").string() + ": ");
#endif
}

}  // namespace
