// One image plane resampled in place through OpenCV maps (the frame's size), for the readers that
// move frames into another camera's pixels (lens_distortion.cpp, color_registration.cpp).
#pragma once
#include <algorithm>
#include <vector>

#include <opencv2/imgproc.hpp>

namespace app {

// `data` ([height, width, channels] of CV type `type`) through map_x / map_y; empty stays empty.
template <typename T>
void remap_plane(std::vector<T>& data, int width, int height, int type, int channels, const cv::Mat& map_x,
                 const cv::Mat& map_y, int interpolation) {
  if (data.empty()) return;
  const cv::Mat in(height, width, CV_MAKETYPE(type, channels), data.data());
  cv::Mat out;
  cv::remap(in, out, map_x, map_y, interpolation, cv::BORDER_REPLICATE);
  std::copy(out.ptr<T>(), out.ptr<T>() + data.size(), data.begin());
}

}  // namespace app
