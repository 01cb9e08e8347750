// Writes ROS 1 bags with Debian's rosbag API, for the tests of gslam's bag input. Built only
// where rosbag is (GSLAM_HAVE_ROS1), as C++17 (the ROS 1 message headers need it).
#pragma once
#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace gslam::test {

class Ros1BagWriter {
 public:
  explicit Ros1BagWriter(const std::string& path);  // throws std::runtime_error
  ~Ros1BagWriter();
  Ros1BagWriter(const Ros1BagWriter&) = delete;
  Ros1BagWriter& operator=(const Ros1BagWriter&) = delete;
  // A sensor_msgs/Image stamped (and recorded) at sec.nsec; rows of width * bytes per pixel.
  void image(const std::string& topic, std::uint32_t sec, std::uint32_t nsec,
             const std::string& encoding, std::uint32_t width, std::uint32_t height,
             std::uint32_t step, const std::vector<std::uint8_t>& data);
  // plumb_bob distortion d (zeros: a rectified camera).
  void camera_info(const std::string& topic, std::uint32_t sec, std::uint32_t nsec,
                   std::uint32_t width, std::uint32_t height, const std::array<double, 9>& k,
                   const std::vector<double>& d = {0, 0, 0, 0, 0});
  // A tf2_msgs/TFMessage with one transform: child's pose in parent (t: x y z, q: x y z w).
  void transform(const std::string& topic, std::uint32_t sec, std::uint32_t nsec,
                 const std::string& parent, const std::string& child,
                 const std::array<double, 3>& t, const std::array<double, 4>& q);
  void close();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace gslam::test
