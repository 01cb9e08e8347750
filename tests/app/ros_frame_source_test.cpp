// The live ROS node's frame source on its own (no ROS graph): the camera from CameraInfo, with its
// plumb_bob distortion undistorting the frames as tracking takes them.
#include "ros/ros_frame_source.h"

#include <gtest/gtest.h>

#include <cstring>

#include "datasets/dataset.h"
#include "datasets/synthetic_sequence.h"
#include "support/temp_dir.h"

namespace {

// A generated frame (raw, through fr1's lens) as the rgb8 and 32FC1 messages a driver sends.
app::ros1::RgbdMessages messages_of(const splat::RgbdFrame& f) {
  app::ros1::RgbdMessages m;
  const auto w = static_cast<std::uint32_t>(f.width()), h = static_cast<std::uint32_t>(f.height());
  m.colour = {1000.0, "rgb8", false, w, h, w * 3, false, {}};
  m.depth = {1000.0, "32FC1", false, w, h, w * 4, false, {}};
  for (float v : f.rgb) m.colour.data.push_back(static_cast<std::uint8_t>(v * 255 + 0.5f));
  m.depth.data.resize(f.depth.size() * 4);
  std::memcpy(m.depth.data.data(), f.depth.data(), m.depth.data.size());
  m.frame_id = "camera";
  return m;
}

TEST(RosFrameSource, CameraInfoDistortionUndistortsTheFramesAsAFolderDoes) {
  gslam::test::TempDir dir;
  app::SyntheticOptions o;
  o.frames = 1;
  o.distortion = {0.262383, -0.953104, -0.005358, 0.002628, 1.163314};
  app::write_synthetic_sequence(dir / "lens", o);
  app::DatasetOptions raw_options;
  raw_options.intrinsics = "260,260,160,120";  // the frames as they are, without undistortion
  const app::Dataset raw = app::open_dataset(dir / "lens", raw_options);
  const app::Dataset folder = app::open_dataset(dir / "lens");  // intrinsics.txt states the lens

  app::RosFrameSource source("test", "", 1.0, 2, [] { return true; });
  app::RosCameraInfo info;
  info.width = 320, info.height = 240;
  info.k = {260, 0, 160, 0, 260, 120, 0, 0, 1};
  info.distortion_model = "plumb_bob";
  info.d = o.distortion.coefficients();
  source.set_camera_info(info);
  source.add(messages_of(raw.load(0)));
  const std::optional<app::ArrivedFrame> arrived = source.next(std::chrono::milliseconds(0));
  ASSERT_TRUE(arrived);
  ASSERT_TRUE(source.undistortion());
  EXPECT_DOUBLE_EQ(source.intrinsics().fx, folder.intrinsics.fx);
  EXPECT_DOUBLE_EQ(arrived->frame.camera.cx, folder.intrinsics.cx);
  const splat::RgbdFrame expected = folder.load(0);
  EXPECT_EQ(arrived->frame.depth, expected.depth);
  ASSERT_EQ(arrived->frame.rgb.size(), expected.rgb.size());
  double worst = 0;
  for (std::size_t i = 0; i < expected.rgb.size(); ++i)
    worst = std::max(worst, double(std::abs(arrived->frame.rgb[i] - expected.rgb[i])));
  EXPECT_LT(worst, 1e-6) << "the same colour as the folder's undistorted frame";
}

}  // namespace
