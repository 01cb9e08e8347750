// The baseline every benchmark table keeps: OpenCV's own dense RGB-D odometry
// (cv::rgbd::RgbdOdometry, Steinbruecker et al. 2011, with OpenCV's default settings), frame to
// frame, with no keyframes, map or back end: what gslam must beat on every sequence.
#pragma once
#include <functional>
#include <vector>

#include "datasets/dataset.h"
#include "io/trajectory.h"

namespace app {

struct BaselineTrajectory {
  std::vector<StampedPose> poses;  // one per frame, camera to world; the first is the world
  std::size_t failures = 0;        // frames OpenCV could not align (the pose is carried over)
};

// Runs the baseline over every frame of `dataset`, calling progress(done, total) after each.
BaselineTrajectory opencv_odometry_baseline(const Dataset& dataset,
                                            const std::function<void(std::size_t, std::size_t)>& progress = {});

}  // namespace app
