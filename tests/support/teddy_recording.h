// The shared teddy frames as ROS messages, for the tests of gslam's ROS input and node: TUM's
// stamps as ROS times, pixels as the messages carry them, the motion capture as /tf, and whole
// ROS 1 bags written with rosbag (GSLAM_HAVE_ROS1 only).
#pragma once
#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "datasets/dataset.h"

namespace gslam::test {

// The shared teddy folder (under ../shared/data), and its first `frames` frames; `intrinsics` as
// the command line's --intrinsics (empty: the folder's own camera).
constexpr char kTeddyFolder[] = "tum_rgbd_fr3_teddy_first200/rgbd_dataset_freiburg3_teddy";
app::Dataset open_teddy(int frames, const std::string& intrinsics = "");

// The TUM fr3 Kinect's calibrated colour camera (as the folder's freiburg3 preset).
constexpr std::array<double, 9> kTeddyK = {535.4, 0, 320.1, 0, 539.2, 247.6, 0, 0, 1};

// "1311867170.462290" -> {1311867170, 462290000}: a TUM stamp as a ROS time, exactly.
std::array<std::uint32_t, 2> ros_time(const std::string& stem);
std::array<std::uint32_t, 2> ros_time(const std::filesystem::path& file);

// Colour as rgb8 (or bgr8) bytes; depth as 32FC1 metres: the folder's own floats.
std::vector<std::uint8_t> colour_bytes(const splat::RgbdFrame& f, bool bgr);
std::vector<std::uint8_t> float_bytes(const std::vector<float>& v);

// Motion capture as TUM's bags publish it: groundtruth.txt's poses of /kinect in /world within
// frames [first, first + count)'s time span (on /tf), and a fixed mount /kinect -> /rgb_optical (on
// /tf_static) that the ground truth must chain through.
struct Transform {
  std::array<std::uint32_t, 2> stamp;
  std::array<double, 3> t;
  std::array<double, 4> q;
};
constexpr std::array<double, 3> kMountT = {0.01, -0.02, 0.03};
constexpr std::array<double, 4> kMountQ = {0, 0, 0.7071067811865476, 0.7071067811865476};  // 90 degrees about z
std::vector<Transform> mocap(const app::Dataset& folder, int first, int count);

#ifdef GSLAM_HAVE_ROS1
// Teddy frames [first, first + count) as TUM's own bags hold them: rgb8 colour on
// /camera/rgb/image_color, 32FC1 depth in metres on /camera/depth/image, CameraInfo with the
// first frame, the motion capture on /tf and the mount on /tf_static.
void write_teddy_bag(const app::Dataset& folder, int first, int count, const std::filesystem::path& out);
#endif

}  // namespace gslam::test
