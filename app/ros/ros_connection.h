// gslam_ros's link to a ROS 1 graph: the only code that includes roscpp. The ROS 1 message
// headers need C++17 (gslam is C++20), so this header holds only plain types and the node's
// logic (ros_node.cpp) stays on gslam's side, where a ROS 2 node could reuse it.
//
// Frames of the map (REP 105): `map` is where gslam's world (the first frame's camera) sits.
// Without an odometry frame, the map is the first camera's pose turned from the optical
// convention (z forward, y down) to the body one (x forward, z up), and map -> camera frame is
// published. With one (`odom_frame`), the map is the odometry frame as it was at the first frame
// and map -> odom is published, so that the robot's own tree (odom -> base -> camera) stays whole.
#pragma once
#include <array>
#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "datasets/bag_reader.h"

namespace app::ros1 {

// A colour and a depth image paired by nearest stamp (within ConnectionOptions::sync_slop).
struct RgbdMessages {
  RosImage colour, depth;
  std::string frame_id;  // the colour image's header.frame_id
  std::chrono::steady_clock::time_point arrived;
};

// The node's private parameters (~name), each as JSON, with nested names joined by '/'
// ("tracking/iterations"), in name order.
using Parameters = std::vector<std::pair<std::string, nlohmann::json>>;

// The `_name:=value` arguments of a command line as roscpp sets them (an integer, else a
// double, else true/false, else a string), for --print-config, which needs no ROS master.
Parameters command_line_parameters(int argc, const char* const* argv);

struct ConnectionOptions {
  std::string map_frame, odom_frame, camera_frame;  // camera_frame empty: the images' frame_id
  double sync_slop = 0;      // seconds between paired colour and depth stamps, at most
  int subscriber_queue = 0;  // messages roscpp keeps per topic before the filter takes them
};

enum class Request { kSave, kReset };

class Connection {
 public:
  // ros::init (gslam handles SIGINT itself); throws splat::Error if no master answers.
  Connection(int argc, char** argv, const std::string& node_name);
  ~Connection();  // shuts the node down
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;

  Parameters parameters() const;
  // "ROS topics /camera/rgb/image_color + /camera/depth/image, camera /camera/rgb/camera_info":
  // the subscribed names as remapped.
  std::string topics() const;

  // Subscribes and advertises; the callbacks run on roscpp's spinner threads. `request` serves
  // the ~save and ~reset services and returns what the service answers (its message).
  void start(const ConnectionOptions& options, std::function<void(RgbdMessages)> frames,
             std::function<void(const RosCameraInfo&)> camera_info,
             std::function<std::pair<bool, std::string>(Request)> request);
  bool ok() const;  // false once ROS shut down (rosnode kill, the master gone)
  // Stops the spinner threads (waiting for callbacks under way) and the subscriptions and
  // services: no callback runs after it returns. The destructor does it too.
  void stop();

  // One tracked frame: map -> camera (or map -> odom) on /tf stamped with the image's stamp, and
  // ~odometry. Takes the map's place from the first call (after reset_map(), the next).
  void publish_pose(double stamp, const std::string& frame_id, const Eigen::Isometry3d& T_world_cam);
  // ~path: every frame's pose as mapping has corrected it.
  void publish_path(const std::vector<std::pair<double, Eigen::Isometry3d>>& T_world_cam);
  // Whether anyone subscribes to ~map_cloud / ~render (the node draws them only then).
  bool wants_cloud() const;
  bool wants_render() const;
  // ~map_cloud: the Gaussians' centres (world frame) with their colour, as PointCloud2 x y z rgb.
  void publish_cloud(double stamp, const std::vector<Eigen::Vector3f>& centres,
                     const std::vector<std::array<std::uint8_t, 3>>& colours);
  // ~render: the map seen from the camera, rgb8, in the camera's frame.
  void publish_render(double stamp, const std::string& frame_id, int width, int height,
                      const std::vector<std::uint8_t>& rgb);
  // The next publish_pose() defines the map anew (after a reset).
  void reset_map();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace app::ros1
