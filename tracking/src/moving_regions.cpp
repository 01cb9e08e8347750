#include "tracking/moving_regions.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <opencv2/imgproc.hpp>

#include "splat/error.h"
#include "splat/field_check.h"

namespace tracking {

void MovingConfig::validate(const std::string& prefix) const {
  const splat::FieldCheck check(prefix);
  check.at_least("max_width", max_width, 8);
  check.at_least("min_change", min_change, 0.0);
  check.at_least("noise_sigmas", noise_sigmas, 0.0);
  check.in_range("min_region", min_region, 0.0, 1.0);
  check.in_range("grow_px", grow_px, 0, 64);
  check.in_range("prior_grow_px", prior_grow_px, 0, 64);
}

std::size_t moving_level(const OdometryFrame& frame, const MovingConfig& config) {
  const std::vector<OdometryFrame::Level>& levels = frame.levels();
  std::size_t level = 0;
  while (level + 1 < levels.size() && levels[level + 1].width <= config.max_width) ++level;
  return level;
}

std::vector<uint8_t> grow_regions(std::span<const uint8_t> labels, int width, int height, int pixels) {
  if (width < 0 || height < 0 ||
      labels.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height)) {
    throw splat::Error("grow_regions: " + std::to_string(labels.size()) + " labels for " +
                       std::to_string(width) + "x" + std::to_string(height));
  }
  std::vector<uint8_t> out(labels.begin(), labels.end());
  if (pixels <= 0) return out;
  cv::Mat any(height, width, CV_8U);
  for (std::size_t i = 0; i < labels.size(); ++i) any.data[i] = labels[i] ? 255 : 0;
  cv::Mat grown;
  cv::dilate(any, grown, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * pixels + 1, 2 * pixels + 1)));
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (!out[i] && grown.data[i]) out[i] = kOutline;
  }
  return out;
}

std::vector<uint8_t> moving_regions(const OdometryFrame& reference, const OdometryFrame& current,
                                    const Eigen::Isometry3d& T_cur_ref, const OdometryConfig& odometry,
                                    const MovingConfig& config, std::span<const uint8_t> previous) {
  const std::size_t level = moving_level(current, config);
  if (reference.levels().size() != current.levels().size()) {
    throw splat::Error("moving_regions: pyramids of " + std::to_string(reference.levels().size()) + " and " +
                       std::to_string(current.levels().size()) + " levels");
  }
  const OdometryFrame::Level& ref = reference.levels()[level];
  const OdometryFrame::Level& cur = current.levels()[level];
  const int w = cur.width, h = cur.height;
  const std::size_t pixels = static_cast<std::size_t>(w) * h;
  if (ref.width != w || ref.height != h || (!previous.empty() && previous.size() != pixels)) {
    throw splat::Error("moving_regions: frames of " + std::to_string(ref.width) + "x" + std::to_string(ref.height) +
                       " and " + std::to_string(w) + "x" + std::to_string(h) + " (previous labels " +
                       std::to_string(previous.size()) + ")");
  }
  // The reference's surfaces in the current frame, nearest depth per pixel: its static ones, and
  // the ones it ignored as moving.
  constexpr float kNone = std::numeric_limits<float>::infinity();
  std::vector<float> warped(pixels, kNone), warped_moving(pixels, kNone);
  const Eigen::Matrix3f r = T_cur_ref.linear().cast<float>();
  const Eigen::Vector3f t = T_cur_ref.translation().cast<float>();
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      const float z = ref.depth[i];
      if (!(z >= odometry.min_depth && z <= odometry.max_depth)) continue;
      const Eigen::Vector3f p_ref(static_cast<float>((x + 0.5 - ref.cx) / ref.fx) * z,
                                  static_cast<float>((y + 0.5 - ref.cy) / ref.fy) * z, z);
      const Eigen::Vector3f p = r * p_ref + t;
      if (!(p.z() > odometry.min_depth)) continue;
      const float u = static_cast<float>(cur.fx) * p.x() / p.z() + static_cast<float>(cur.cx);
      const float v = static_cast<float>(cur.fy) * p.y() / p.z() + static_cast<float>(cur.cy);
      if (!(u >= 0 && v >= 0 && u < static_cast<float>(w) && v < static_cast<float>(h))) continue;
      const uint8_t ignored = ref.ignore.empty() ? 0 : ref.ignore[i];
      if (ignored != 0 && ignored < kMovingSurface) continue;  // neither static nor known to move
      const bool moving = ignored >= kMovingSurface;
      float& slot = (moving ? warped_moving : warped)[static_cast<std::size_t>(v) * w + static_cast<std::size_t>(u)];
      slot = std::min(slot, p.z());
    }
  }
  // Changed pixels: in front of the nearest or behind the farthest static surface around them.
  // Continuing pixels: at (or in front of) a moving surface of the reference.
  std::vector<uint8_t> changed(pixels, kStaticPixel), continuing(pixels, 0);
  cv::Mat any(h, w, CV_8U, cv::Scalar(0));
  for (int y = 1; y + 1 < h; ++y) {
    for (int x = 1; x + 1 < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      const float z = cur.depth[i];
      if (!(z >= odometry.min_depth && z <= odometry.max_depth)) continue;
      float nearest = kNone, farthest = 0, farthest_moving = 0;
      int seen = 0;
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const std::size_t j = i + static_cast<std::ptrdiff_t>(dy) * w + dx;
          if (warped_moving[j] != kNone) farthest_moving = std::max(farthest_moving, warped_moving[j]);
          if (warped[j] == kNone) continue;
          nearest = std::min(nearest, warped[j]);
          farthest = std::max(farthest, warped[j]);
          ++seen;
        }
      }
      const float tolerance = static_cast<float>(config.min_change + config.noise_sigmas * odometry.depth_noise * z * z);
      if (farthest_moving > 0) {
        // Behind a moving surface, and not on a static one beside it: the object left here.
        continuing[i] = z < farthest_moving + tolerance;
        const bool on_static = seen > 0 && z >= nearest - tolerance && z <= farthest + tolerance;
        if (!continuing[i] && !on_static) changed[i] = kLeft;
      } else if (seen >= 3) {  // fewer: too little of the reference lands here to judge
        if (z < nearest - tolerance) {
          changed[i] = kArrived;
        } else if (z > farthest + tolerance) {
          changed[i] = kLeft;
        }
      }
      if (changed[i] || continuing[i]) any.at<uint8_t>(y, x) = 255;
    }
  }
  std::vector<uint8_t> labels(pixels, kStaticPixel);
  if (cv::countNonZero(any) == 0) return labels;  // the usual case: nothing moved
  // Regions of changed and continuing pixels. One is kept if enough of it changed: an object
  // keeps uncovering or covering the scene while it moves, and once it stops it joins the scene.
  cv::Mat components, stats, centroids;
  const int count = cv::connectedComponentsWithStats(any, components, stats, centroids, 4, CV_32S);
  std::vector<std::size_t> changed_area(static_cast<std::size_t>(count), 0);
  std::vector<uint8_t> continues(static_cast<std::size_t>(count), 0);
  for (std::size_t i = 0; i < pixels; ++i) {
    const auto c = static_cast<std::size_t>(components.ptr<int>()[i]);
    changed_area[c] += changed[i] != kStaticPixel;
    if (continuing[i] || (!previous.empty() && previous[i])) continues[c] = 1;
  }
  const double min_area = config.min_region * static_cast<double>(pixels);
  std::vector<uint8_t> kept(static_cast<std::size_t>(count), 0);
  for (std::size_t c = 1; c < kept.size(); ++c) {
    const auto area = static_cast<double>(changed_area[c]);
    kept[c] = area >= min_area || (continues[c] && area >= min_area / 2);
  }
  for (std::size_t i = 0; i < pixels; ++i) {
    if (kept[static_cast<std::size_t>(components.ptr<int>()[i])]) labels[i] = continuing[i] ? static_cast<uint8_t>(kArrived) : changed[i];
  }
  return grow_regions(labels, w, h, config.grow_px);
}

}  // namespace tracking
