// gslam_ros: the ROS 1 node (ros/ros_node.h); this only turns errors into one line.
#include <cstdio>
#include <exception>

#include "ros/ros_node.h"

int main(int argc, char** argv) {
  try {
    return app::run_ros_node(argc, argv);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "gslam_ros: error: %s\n", e.what());
    return 1;
  }
}
