// Recordings of ROS messages as gslam input: a ROS 1 .bag (read with Debian's rosbag where it is
// installed) or an MCAP file (ROS 2's default, read by gslam itself). A reader indexes the file
// once (topics, and for image topics each message's stamp, encoding and size) and reads one
// message at a time afterwards, so a recording is never held in memory.
#pragma once
#include <array>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace app {

// sensor_msgs/Image or sensor_msgs/CompressedImage as recorded.
struct RosImage {
  double stamp = 0;  // header.stamp, seconds
  std::string
      encoding;  // Image: "rgb8", "16UC1", ...; CompressedImage: its format ("png", "jpeg", ...)
  bool compressed = false;                        // a CompressedImage
  std::uint32_t width = 0, height = 0, step = 0;  // Image only; step in bytes per row
  bool big_endian = false;                        // Image only
  std::vector<std::uint8_t> data;  // [height, step] rows or the compressed file; empty in an index
};

// sensor_msgs/CameraInfo: the image size, the 3x3 camera matrix and the lens distortion.
struct RosCameraInfo {
  std::uint32_t width = 0, height = 0;
  std::array<double, 9> k{};  // row-major: fx 0 cx, 0 fy cy, 0 0 1
  std::string distortion_model;  // "plumb_bob", ...
  std::vector<double> d;         // its coefficients
  std::array<double, 12>
      p{};  // row-major 3x4: the rectified images' camera (fx' 0 cx' 0, 0 fy' cy' 0, ...)
};

// ROS's image_proc convention: a CameraInfo describes the raw images, and images on a topic
// named *rect* (image_rect, image_rect_color) are already rectified into the camera P, without
// distortion. For such a topic the camera is P's (where it is given) and D is none.
inline bool is_rectified_topic(const std::string& topic) {
  return topic.find("rect") != std::string::npos;
}
inline void use_rectified_camera(RosCameraInfo& info) {
  if (info.p[0] > 0 && info.p[5] > 0)
    info.k = {info.p[0], 0, info.p[2], 0, info.p[5], info.p[6], 0, 0, 1};
  info.d.clear();
}

// One transform of a tf2_msgs/TFMessage (ROS 1's tf/tfMessage alike): the pose of frame
// `child` in frame `parent` at `stamp`, p_parent = T_parent_child * p_child.
struct RosTransform {
  double stamp = 0;           // header.stamp, seconds
  std::string parent, child;  // frame ids without a leading '/'
  std::array<double, 3> translation{};
  std::array<double, 4> rotation{0, 0, 0, 1};  // quaternion x, y, z, w
  bool is_static = false;                      // from /tf_static: valid at every time
};

struct BagTopic {
  std::string name;
  std::string type;  // ROS 1 spelling: "sensor_msgs/Image" (ROS 2's "sensor_msgs/msg/Image" too)
  std::size_t messages = 0;
};

class BagReader {
 public:
  virtual ~BagReader() = default;
  virtual const std::filesystem::path& path() const = 0;
  // Every topic with its message type and count, in name order.
  virtual std::vector<BagTopic> topics() const = 0;
  // The messages of an Image or CompressedImage topic in recording order, without their pixels
  // (data empty). Throws splat::Error naming the file and topic for a malformed message.
  virtual std::vector<RosImage> image_index(const std::string& topic) const = 0;
  // The first message of image_index(topic) (nullopt for none), as cheaply as the format allows:
  // topics are told apart by it before one is indexed.
  virtual std::optional<RosImage> first_image(const std::string& topic) const {
    std::vector<RosImage> index = image_index(topic);
    if (index.empty()) return std::nullopt;
    return std::move(index.front());
  }
  // Message k of image_index(topic), with its pixels. Safe to call from several threads.
  virtual RosImage read_image(const std::string& topic, std::size_t k) const = 0;
  // The first CameraInfo message on `topic`; nullopt when it has none.
  virtual std::optional<RosCameraInfo> camera_info(const std::string& topic) const = 0;
  // Every transform of the TFMessage topics (/tf, /tf_static), each topic's in recording order.
  // Throws splat::Error naming the file for a malformed message.
  virtual std::vector<RosTransform> transforms() const = 0;
};

// ".bag" or ".mcap" (any case): a recording rather than a dataset folder.
bool is_bag_file(const std::filesystem::path& path);

// Opens an MCAP file (chunks uncompressed, zstd or lz4; messages CDR as ROS 2 writes them, or
// ROS 1 serialized). Throws splat::Error naming the file: not MCAP, truncated, a record or chunk
// whose sizes do not fit, an unknown compression.
std::unique_ptr<BagReader> open_mcap(const std::filesystem::path& path);

// Opens a ROS 1 bag (format 2.0, indexed). Throws splat::Error naming the file when it cannot be
// read (unindexed: `rosbag reindex`), or when gslam was built without ROS (ros1_bag_supported()).
std::unique_ptr<BagReader> open_ros1_bag(const std::filesystem::path& path);
bool ros1_bag_supported();

}  // namespace app
