#include "batch/opencv_baseline.h"

#include <algorithm>

#include <opencv2/core/eigen.hpp>
#include <opencv2/rgbd.hpp>

namespace app {
namespace {

// RgbdOdometry's inputs: 8-bit grey and depth in metres (0: none).
void to_opencv(const splat::RgbdFrame& frame, cv::Mat& grey, cv::Mat& depth) {
  const int w = frame.width(), h = frame.height();
  grey.create(h, w, CV_8UC1);
  depth.create(h, w, CV_32FC1);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t p = static_cast<std::size_t>(y) * w + x;
      const float* c = &frame.rgb[p * 3];
      const float luma = 0.299f * c[0] + 0.587f * c[1] + 0.114f * c[2];
      grey.at<uint8_t>(y, x) = static_cast<uint8_t>(std::clamp(luma, 0.f, 1.f) * 255.f + 0.5f);
      depth.at<float>(y, x) = frame.depth[p];
    }
  }
}

}  // namespace

BaselineTrajectory opencv_odometry_baseline(const Dataset& dataset,
                                            const std::function<void(std::size_t, std::size_t)>& progress) {
  BaselineTrajectory out;
  const splat::Camera& k = dataset.intrinsics;
  const cv::Mat camera = (cv::Mat_<float>(3, 3) << static_cast<float>(k.fx), 0, static_cast<float>(k.cx), 0,
                          static_cast<float>(k.fy), static_cast<float>(k.cy), 0, 0, 1);
  const cv::Ptr<cv::rgbd::RgbdOdometry> odometry = cv::rgbd::RgbdOdometry::create(camera);
  cv::Mat previous_grey, previous_depth, grey, depth;
  Eigen::Isometry3d T_world_cam = Eigen::Isometry3d::Identity();
  for (std::size_t i = 0; i < dataset.entries.size(); ++i) {
    to_opencv(dataset.load(i), grey, depth);
    if (i > 0) {
      // Rt maps points of the source (previous) frame into the destination (current) one.
      cv::Mat Rt;
      if (odometry->compute(previous_grey, previous_depth, cv::Mat(), grey, depth, cv::Mat(), Rt)) {
        Eigen::Matrix4d T_cur_prev;
        cv::cv2eigen(Rt, T_cur_prev);
        T_world_cam = T_world_cam * Eigen::Isometry3d(T_cur_prev).inverse();
      } else {
        ++out.failures;
      }
    }
    out.poses.push_back({dataset.entries[i].timestamp, T_world_cam});
    std::swap(previous_grey, grey);
    std::swap(previous_depth, depth);
    if (progress) progress(i + 1, dataset.entries.size());
  }
  return out;
}

}  // namespace app
