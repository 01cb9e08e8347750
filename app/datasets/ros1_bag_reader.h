// ROS 1 bags (format 2.0) through Debian's rosbag C++ API: open_ros1_bag() in bag_reader.h.
// Built only where rosbag is installed (GSLAM_HAVE_ROS1); without it, open_ros1_bag() throws a
// splat::Error naming the apt packages. Compiled as C++17: the ROS 1 message headers use
// std::allocator members that C++20 removed.
#pragma once
#include "datasets/bag_reader.h"
