// gslam_ros: `gslam live` as a ROS 1 node. The same SlamSystem and run folder as `gslam live`;
// frames come from the topics rgb/image + depth/image (paired by nearest stamp) with the camera
// from rgb/camera_info, and every tracked frame is published (ros_connection.h: /tf, ~odometry,
// ~path, ~map_cloud, ~render). Services ~save and ~reset. SIGINT ends the run and writes it.
#pragma once
#include <filesystem>
#include <string>

namespace app {

// The node's own private parameters (~name); every other ~name is a SLAM setting, by the names
// `gslam_ros --print-config` lists (e.g. ~keyframe_every, ~tracking/iterations).
struct RosNodeOptions {
  std::filesystem::path out = "gslam_run";  // the run folder (relative: to the node's working folder)
  bool overwrite = false;                   // replace another run's outputs in `out`
  std::filesystem::path config;             // JSON SLAM settings, under the parameters
  std::string backend = "auto";             // auto | cpu | vulkan
  int threads = 0;                          // CPU backend threads; 0: all
  std::string intrinsics;  // "fx,fy,cx,cy[,k1,k2,p1,p2,k3]"; empty: from rgb/camera_info
  double depth_scale = 0;                   // stored depth per metre; 0: by the encoding (16UC1 mm, 32FC1 m)
  int queue_size = 1;                       // frames waiting for tracking; 1: the newest only, as a camera
  double sync_slop = 0.02;                  // seconds between paired colour and depth stamps, at most
  std::string map_frame = "map";
  std::string odom_frame;    // set: publish map -> odom (the robot's odometry), not map -> camera
  std::string camera_frame;  // empty: the colour images' frame_id
  double path_period = 0.5;    // seconds between ~path messages
  double cloud_period = 2;     // seconds between ~map_cloud messages (only while subscribed)
  double render_period = 0.5;  // seconds between ~render images (only while subscribed)
  int render_width = 320;      // ~render's width in pixels (height as the camera's aspect)
  double checkpoint_seconds = 30;  // the run folder rewritten this often
  bool catch_up = true;            // at the end, map the keyframes mapping skipped
};

// The node's main: argv as roscpp takes it (remappings, _name:=value). With --print-config, writes
// the effective SLAM settings as JSON (defaults, ~config, the _name:=value arguments) and stops,
// with no ROS master needed.
int run_ros_node(int argc, char** argv);

}  // namespace app
