// Compiled as C++17 (the ROS 1 message headers need it); see ros_connection.h.
#include "ros/ros_connection.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <mutex>

#include <geometry_msgs/TransformStamped.h>
#include <deque>
#include <nav_msgs/Odometry.h>
#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>
#include <std_srvs/Trigger.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include "splat/error.h"

namespace app::ros1 {
namespace {

nlohmann::json to_json(XmlRpc::XmlRpcValue& v) {
  switch (v.getType()) {
    case XmlRpc::XmlRpcValue::TypeBoolean: return static_cast<bool>(v);
    case XmlRpc::XmlRpcValue::TypeInt: return static_cast<int>(v);
    case XmlRpc::XmlRpcValue::TypeDouble: return static_cast<double>(v);
    case XmlRpc::XmlRpcValue::TypeString: return static_cast<std::string>(v);
    case XmlRpc::XmlRpcValue::TypeArray: {
      nlohmann::json out = nlohmann::json::array();
      for (int i = 0; i < v.size(); ++i) out.push_back(to_json(v[i]));
      return out;
    }
    case XmlRpc::XmlRpcValue::TypeStruct: {
      nlohmann::json out = nlohmann::json::object();
      for (auto& [key, value] : v) out[key] = to_json(value);
      return out;
    }
    default: return v.toXml();
  }
}

RosImage to_ros_image(const sensor_msgs::Image& m) {
  RosImage out;
  out.stamp = m.header.stamp.toSec();
  out.encoding = m.encoding;
  out.width = m.width;
  out.height = m.height;
  out.step = m.step;
  out.big_endian = m.is_bigendian != 0;
  out.data = m.data;
  return out;
}

geometry_msgs::Transform to_msg(const Eigen::Isometry3d& T) {
  geometry_msgs::Transform out;
  const Eigen::Quaterniond q(T.rotation());
  out.translation.x = T.translation().x();
  out.translation.y = T.translation().y();
  out.translation.z = T.translation().z();
  out.rotation.x = q.x();
  out.rotation.y = q.y();
  out.rotation.z = q.z();
  out.rotation.w = q.w();
  return out;
}

geometry_msgs::Pose to_pose(const Eigen::Isometry3d& T) {
  const geometry_msgs::Transform t = to_msg(T);
  geometry_msgs::Pose out;
  out.position.x = t.translation.x;
  out.position.y = t.translation.y;
  out.position.z = t.translation.z;
  out.orientation = t.rotation;
  return out;
}

Eigen::Isometry3d from_msg(const geometry_msgs::Transform& t) {
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = Eigen::Quaterniond(t.rotation.w, t.rotation.x, t.rotation.y, t.rotation.z)
                   .normalized()
                   .toRotationMatrix();
  T.translation() = Eigen::Vector3d(t.translation.x, t.translation.y, t.translation.z);
  return T;
}

// The body frame (x forward, y left, z up) from the optical one (x right, y down, z forward).
Eigen::Isometry3d body_from_optical() {
  Eigen::Matrix3d R;
  R << 0, 0, 1, -1, 0, 0, 0, -1, 0;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = R;
  return T;
}

std::string without_slash(std::string frame) {
  while (!frame.empty() && frame.front() == '/') frame.erase(frame.begin());
  return frame;
}

}  // namespace

Parameters command_line_parameters(int argc, const char* const* argv) {
  Parameters out;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    const auto at = arg.find(":=");
    if (at == std::string::npos || at < 2 || arg[0] != '_' || arg[1] == '_') continue;
    const std::string name = arg.substr(1, at - 1), text = arg.substr(at + 2);
    nlohmann::json value = text;
    char* end = nullptr;
    const long n = std::strtol(text.c_str(), &end, 10);
    if (!text.empty() && *end == '\0' && n >= INT32_MIN && n <= INT32_MAX) {
      value = static_cast<int>(n);
    } else {
      const double d = std::strtod(text.c_str(), &end);
      if (!text.empty() && *end == '\0') {
        value = d;
      } else if (text == "true" || text == "True" || text == "TRUE") {
        value = true;
      } else if (text == "false" || text == "False" || text == "FALSE") {
        value = false;
      }
    }
    out.emplace_back(name, value);
  }
  return out;
}

struct Connection::Impl {
  std::optional<ros::NodeHandle> nh, pnh;
  std::optional<ros::AsyncSpinner> spinner;
  ConnectionOptions options;
  ros::Subscriber colour_sub, depth_sub, info_sub;
  ros::ServiceServer save_srv, reset_srv;
  ros::Publisher odometry_pub, path_pub, cloud_pub, render_pub;
  std::optional<tf2_ros::TransformBroadcaster> broadcaster;
  std::optional<tf2_ros::Buffer> tf_buffer;
  std::optional<tf2_ros::TransformListener> tf_listener;
  std::function<std::pair<bool, std::string>(Request)> request;
  std::function<void(RgbdMessages)> frames;

  // Approximate-time pairing that never waits: an image is paired, as it arrives, with the waiting
  // image of the other kind nearest in stamp within sync_slop (message_filters' ApproximateTime
  // would hold each pair until the next message, a frame's period of latency, and the last pair
  // of a stream for ever). Older images of either kind are then dropped: they can no longer be
  // paired in order.
  std::mutex pairing_mutex;
  std::deque<sensor_msgs::ImageConstPtr> waiting[2];  // colour, depth
  static constexpr std::size_t kWaiting = 30;

  void on_image(int kind, const sensor_msgs::ImageConstPtr& image) {
    sensor_msgs::ImageConstPtr partner;
    {
      std::lock_guard lock(pairing_mutex);
      auto& others = waiting[1 - kind];
      const double t = image->header.stamp.toSec();
      std::ptrdiff_t best = -1;
      double best_dt = options.sync_slop;
      for (std::size_t i = 0; i < others.size(); ++i) {
        const double dt = std::abs(others[i]->header.stamp.toSec() - t);
        if (dt <= best_dt) best = std::ptrdiff_t(i), best_dt = dt;
      }
      if (best < 0) {
        auto& mine = waiting[kind];
        mine.push_back(image);
        if (mine.size() > kWaiting) mine.pop_front();
        return;
      }
      partner = others[std::size_t(best)];
      others.erase(others.begin(), others.begin() + best + 1);
      auto& mine = waiting[kind];
      while (!mine.empty() && mine.front()->header.stamp <= image->header.stamp) mine.pop_front();
    }
    if (kind == 0) {
      on_pair(image, partner);
    } else {
      on_pair(partner, image);
    }
  }

  void on_pair(const sensor_msgs::ImageConstPtr& colour, const sensor_msgs::ImageConstPtr& depth) {
    RgbdMessages out;
    out.arrived = std::chrono::steady_clock::now();
    out.colour = to_ros_image(*colour);
    out.depth = to_ros_image(*depth);
    out.frame_id = colour->header.frame_id;
    frames(std::move(out));
  }

  std::mutex mutex;  // guards what follows (the pipeline publishes, a reset may come)
  std::optional<Eigen::Isometry3d> T_map_world;

  std::string camera_frame(const std::string& image_frame) const {
    if (!options.camera_frame.empty()) return without_slash(options.camera_frame);
    const std::string f = without_slash(image_frame);
    return f.empty() ? "camera" : f;
  }

  // T_odom_cam at `stamp`, waiting briefly for odometry that lags the image.
  std::optional<Eigen::Isometry3d> odom_pose(const std::string& camera, double stamp) {
    try {
      const auto t = tf_buffer->lookupTransform(options.odom_frame, camera, ros::Time(stamp),
                                                ros::Duration(0.03));
      return from_msg(t.transform);
    } catch (const tf2::TransformException& e) {
      ROS_WARN_THROTTLE(5, "gslam: no %s -> %s transform at %.3f (%s): map -> %s not published",
                        options.odom_frame.c_str(), camera.c_str(), stamp, e.what(),
                        options.odom_frame.c_str());
      return std::nullopt;
    }
  }

  bool serve(Request kind, std_srvs::Trigger::Response& response) {
    const auto [ok, message] = request(kind);
    response.success = ok;
    response.message = message;
    return true;
  }
};

Connection::Connection(int argc, char** argv, const std::string& node_name) : impl_(std::make_unique<Impl>()) {
  int n = argc;
  ros::init(n, argv, node_name, ros::init_options::NoSigintHandler);
  if (!ros::master::check()) {
    throw splat::Error("gslam_ros: no ROS master answers at " + ros::master::getURI() +
                       " (start roscore, or set ROS_MASTER_URI)");
  }
  impl_->nh.emplace();
  impl_->pnh.emplace("~");
}

Connection::~Connection() {
  stop();
  ros::shutdown();
}

void Connection::stop() {
  Impl& m = *impl_;
  if (m.spinner) m.spinner->stop();
  for (ros::Subscriber* s : {&m.colour_sub, &m.depth_sub, &m.info_sub}) s->shutdown();
  m.save_srv.shutdown();
  m.reset_srv.shutdown();
}

Parameters Connection::parameters() const {
  std::vector<std::string> names;
  ros::param::getParamNames(names);
  const std::string prefix = ros::this_node::getName() + "/";
  Parameters out;
  for (const std::string& name : names) {
    if (name.rfind(prefix, 0) != 0) continue;
    XmlRpc::XmlRpcValue value;
    if (ros::param::get(name, value)) out.emplace_back(name.substr(prefix.size()), to_json(value));
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  return out;
}

std::string Connection::topics() const {
  return "ROS topics " + ros::names::resolve("rgb/image") + " + " + ros::names::resolve("depth/image") + ", camera " +
         ros::names::resolve("rgb/camera_info");
}

void Connection::start(const ConnectionOptions& options, std::function<void(RgbdMessages)> frames,
                       std::function<void(const RosCameraInfo&)> camera_info,
                       std::function<std::pair<bool, std::string>(Request)> request) {
  Impl& m = *impl_;
  m.options = options;
  m.options.map_frame = without_slash(options.map_frame);
  m.options.odom_frame = without_slash(options.odom_frame);
  m.request = std::move(request);
  ros::NodeHandle& nh = *m.nh;
  ros::NodeHandle& pnh = *m.pnh;
  m.broadcaster.emplace();
  if (!m.options.odom_frame.empty()) {
    m.tf_buffer.emplace();
    m.tf_listener.emplace(*m.tf_buffer);
  }
  m.odometry_pub = pnh.advertise<nav_msgs::Odometry>("odometry", 10);
  m.path_pub = pnh.advertise<nav_msgs::Path>("path", 1, true);
  m.cloud_pub = pnh.advertise<sensor_msgs::PointCloud2>("map_cloud", 1, true);
  m.render_pub = pnh.advertise<sensor_msgs::Image>("render", 1);
  const uint32_t queue = static_cast<uint32_t>(std::max(1, options.subscriber_queue));
  m.frames = std::move(frames);
  m.colour_sub = nh.subscribe<sensor_msgs::Image>(
      "rgb/image", queue, [&m](const sensor_msgs::ImageConstPtr& image) { m.on_image(0, image); });
  m.depth_sub = nh.subscribe<sensor_msgs::Image>(
      "depth/image", queue, [&m](const sensor_msgs::ImageConstPtr& image) { m.on_image(1, image); });
  m.info_sub = nh.subscribe<sensor_msgs::CameraInfo>(
      "rgb/camera_info", 1, [camera_info = std::move(camera_info)](const sensor_msgs::CameraInfoConstPtr& info) {
        RosCameraInfo out;
        out.width = info->width;
        out.height = info->height;
        std::copy(info->K.begin(), info->K.end(), out.k.begin());
        out.distortion_model = info->distortion_model;
        out.d.assign(info->D.begin(), info->D.end());
        std::copy(info->P.begin(), info->P.end(), out.p.begin());
        if (is_rectified_topic(ros::names::resolve("rgb/image"))) use_rectified_camera(out);
        camera_info(out);
      });
  m.save_srv = pnh.advertiseService<std_srvs::Trigger::Request, std_srvs::Trigger::Response>(
      "save", [&m](std_srvs::Trigger::Request&, std_srvs::Trigger::Response& r) { return m.serve(Request::kSave, r); });
  m.reset_srv = pnh.advertiseService<std_srvs::Trigger::Request, std_srvs::Trigger::Response>(
      "reset", [&m](std_srvs::Trigger::Request&, std_srvs::Trigger::Response& r) { return m.serve(Request::kReset, r); });
  // Two threads: a service waits for the pipeline while frames keep coming.
  m.spinner.emplace(2);
  m.spinner->start();
}

bool Connection::ok() const { return ros::ok(); }

void Connection::publish_pose(double stamp, const std::string& frame_id, const Eigen::Isometry3d& T_world_cam) {
  Impl& m = *impl_;
  const std::string camera = m.camera_frame(frame_id);
  const bool odom = !m.options.odom_frame.empty();
  std::optional<Eigen::Isometry3d> T_odom_cam;
  if (odom) {
    T_odom_cam = m.odom_pose(camera, stamp);
    if (!T_odom_cam) return;
  }
  Eigen::Isometry3d T_map_cam;
  {
    std::lock_guard lock(m.mutex);
    if (!m.T_map_world) {
      m.T_map_world = (odom ? *T_odom_cam : body_from_optical()) * T_world_cam.inverse();
    }
    T_map_cam = *m.T_map_world * T_world_cam;
  }
  geometry_msgs::TransformStamped tf;
  tf.header.stamp = ros::Time(stamp);
  tf.header.frame_id = m.options.map_frame;
  if (odom) {
    tf.child_frame_id = m.options.odom_frame;
    tf.transform = to_msg(T_map_cam * T_odom_cam->inverse());
  } else {
    tf.child_frame_id = camera;
    tf.transform = to_msg(T_map_cam);
  }
  m.broadcaster->sendTransform(tf);
  nav_msgs::Odometry odometry;
  odometry.header = tf.header;
  odometry.child_frame_id = camera;
  odometry.pose.pose = to_pose(T_map_cam);
  m.odometry_pub.publish(odometry);
}

void Connection::publish_path(const std::vector<std::pair<double, Eigen::Isometry3d>>& T_world_cam) {
  Impl& m = *impl_;
  Eigen::Isometry3d T_map_world;
  {
    std::lock_guard lock(m.mutex);
    if (!m.T_map_world || T_world_cam.empty()) return;
    T_map_world = *m.T_map_world;
  }
  nav_msgs::Path path;
  path.header.stamp = ros::Time(T_world_cam.back().first);
  path.header.frame_id = m.options.map_frame;
  path.poses.resize(T_world_cam.size());
  for (std::size_t i = 0; i < T_world_cam.size(); ++i) {
    path.poses[i].header.stamp = ros::Time(T_world_cam[i].first);
    path.poses[i].header.frame_id = m.options.map_frame;
    path.poses[i].pose = to_pose(T_map_world * T_world_cam[i].second);
  }
  m.path_pub.publish(path);
}

bool Connection::wants_cloud() const { return impl_->cloud_pub.getNumSubscribers() > 0; }
bool Connection::wants_render() const { return impl_->render_pub.getNumSubscribers() > 0; }

void Connection::publish_cloud(double stamp, const std::vector<Eigen::Vector3f>& centres,
                               const std::vector<std::array<std::uint8_t, 3>>& colours) {
  Impl& m = *impl_;
  Eigen::Isometry3f T_map_world;
  {
    std::lock_guard lock(m.mutex);
    if (!m.T_map_world) return;
    T_map_world = m.T_map_world->cast<float>();
  }
  sensor_msgs::PointCloud2 cloud;
  cloud.header.stamp = ros::Time(stamp);
  cloud.header.frame_id = m.options.map_frame;
  cloud.height = 1;
  cloud.width = static_cast<uint32_t>(centres.size());
  const char* names[] = {"x", "y", "z", "rgb"};
  for (uint32_t k = 0; k < 4; ++k) {
    sensor_msgs::PointField f;
    f.name = names[k];
    f.offset = 4 * k;
    f.datatype = sensor_msgs::PointField::FLOAT32;
    f.count = 1;
    cloud.fields.push_back(f);
  }
  cloud.point_step = 16;
  cloud.row_step = cloud.point_step * cloud.width;
  cloud.is_dense = true;
  cloud.data.resize(std::size_t(cloud.row_step));
  for (std::size_t i = 0; i < centres.size(); ++i) {
    const Eigen::Vector3f p = T_map_world * centres[i];
    // RViz's packed colour: 0x00RRGGBB in the bytes of a float.
    const uint32_t rgb = uint32_t(colours[i][0]) << 16 | uint32_t(colours[i][1]) << 8 | colours[i][2];
    uint8_t* out = cloud.data.data() + i * 16;
    std::memcpy(out, p.data(), 12);
    std::memcpy(out + 12, &rgb, 4);
  }
  m.cloud_pub.publish(cloud);
}

void Connection::publish_render(double stamp, const std::string& frame_id, int width, int height,
                                const std::vector<std::uint8_t>& rgb) {
  sensor_msgs::Image image;
  image.header.stamp = ros::Time(stamp);
  image.header.frame_id = impl_->camera_frame(frame_id);
  image.width = static_cast<uint32_t>(width);
  image.height = static_cast<uint32_t>(height);
  image.encoding = "rgb8";
  image.step = static_cast<uint32_t>(width * 3);
  image.data = rgb;
  impl_->render_pub.publish(image);
}

void Connection::reset_map() {
  std::lock_guard lock(impl_->mutex);
  impl_->T_map_world.reset();
}

}  // namespace app::ros1
