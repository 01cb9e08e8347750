#include "support/ros1_bag_writer.h"

#include <rosbag/bag.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>

namespace gslam::test {

struct Ros1BagWriter::Impl {
  rosbag::Bag bag;
};

Ros1BagWriter::Ros1BagWriter(const std::string& path) : impl_(std::make_unique<Impl>()) {
  impl_->bag.open(path, rosbag::bagmode::Write);
}

Ros1BagWriter::~Ros1BagWriter() = default;

void Ros1BagWriter::image(const std::string& topic, std::uint32_t sec, std::uint32_t nsec, const std::string& encoding,
                          std::uint32_t width, std::uint32_t height, std::uint32_t step,
                          const std::vector<std::uint8_t>& data) {
  sensor_msgs::Image m;
  m.header.stamp = ros::Time(sec, nsec);
  m.header.frame_id = "camera";
  m.width = width;
  m.height = height;
  m.encoding = encoding;
  m.is_bigendian = 0;
  m.step = step;
  m.data = data;
  impl_->bag.write(topic, m.header.stamp, m);
}

void Ros1BagWriter::camera_info(const std::string& topic, std::uint32_t sec, std::uint32_t nsec, std::uint32_t width,
                                std::uint32_t height, const std::array<double, 9>& k) {
  sensor_msgs::CameraInfo m;
  m.header.stamp = ros::Time(sec, nsec);
  m.header.frame_id = "camera";
  m.width = width;
  m.height = height;
  m.distortion_model = "plumb_bob";
  m.D = {0, 0, 0, 0, 0};
  for (std::size_t i = 0; i < 9; ++i) m.K[i] = k[i];
  impl_->bag.write(topic, m.header.stamp, m);
}

void Ros1BagWriter::close() { impl_->bag.close(); }

}  // namespace gslam::test
