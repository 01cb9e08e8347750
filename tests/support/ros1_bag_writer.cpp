#include "support/ros1_bag_writer.h"

#include <rosbag/bag.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <tf2_msgs/TFMessage.h>

namespace gslam::test {

struct Ros1BagWriter::Impl {
  rosbag::Bag bag;
};

Ros1BagWriter::Ros1BagWriter(const std::string& path) : impl_(std::make_unique<Impl>()) {
  impl_->bag.open(path, rosbag::bagmode::Write);
}

Ros1BagWriter::~Ros1BagWriter() = default;

void Ros1BagWriter::image(const std::string& topic, std::uint32_t sec, std::uint32_t nsec,
                          const std::string& encoding, std::uint32_t width, std::uint32_t height,
                          std::uint32_t step, const std::vector<std::uint8_t>& data) {
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

void Ros1BagWriter::camera_info(const std::string& topic, std::uint32_t sec, std::uint32_t nsec,
                                std::uint32_t width, std::uint32_t height,
                                const std::array<double, 9>& k, const std::vector<double>& d) {
  sensor_msgs::CameraInfo m;
  m.header.stamp = ros::Time(sec, nsec);
  m.header.frame_id = "camera";
  m.width = width;
  m.height = height;
  m.distortion_model = "plumb_bob";
  m.D = d;
  for (std::size_t i = 0; i < 9; ++i) m.K[i] = k[i];
  impl_->bag.write(topic, m.header.stamp, m);
}

void Ros1BagWriter::transform(const std::string& topic, std::uint32_t sec, std::uint32_t nsec,
                              const std::string& parent, const std::string& child,
                              const std::array<double, 3>& t, const std::array<double, 4>& q) {
  geometry_msgs::TransformStamped ts;
  ts.header.stamp = ros::Time(sec, nsec);
  ts.header.frame_id = parent;
  ts.child_frame_id = child;
  ts.transform.translation.x = t[0], ts.transform.translation.y = t[1],
  ts.transform.translation.z = t[2];
  ts.transform.rotation.x = q[0], ts.transform.rotation.y = q[1], ts.transform.rotation.z = q[2],
  ts.transform.rotation.w = q[3];
  tf2_msgs::TFMessage m;
  m.transforms.push_back(ts);
  impl_->bag.write(topic, ts.header.stamp, m);
}

void Ros1BagWriter::close() { impl_->bag.close(); }

}  // namespace gslam::test
