#include "datasets/lens_distortion.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>

#include "datasets/remap_plane.h"
#include "splat/error.h"

namespace app {

LensDistortion lens_distortion_from(const std::vector<double>& c, const std::string& what) {
  if (c.size() != 4 && c.size() != 5) {
    throw splat::Error(what + ": expected 4 or 5 distortion coefficients k1,k2,p1,p2[,k3], got " +
                       std::to_string(c.size()));
  }
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (!std::isfinite(c[i]) || std::abs(c[i]) >= 100) {
      static const char* const kNames[] = {"k1", "k2", "p1", "p2", "k3"};
      char value[32];
      std::snprintf(value, sizeof(value), "%g", c[i]);
      throw splat::Error(what + ": distortion " + kNames[i] + " is " + value +
                         " (expected a finite number under 100)");
    }
  }
  return {c[0], c[1], c[2], c[3], c.size() == 5 ? c[4] : 0.0};
}

std::vector<Eigen::Vector2d> undistort_normalized(const LensDistortion& d,
                                                  const std::vector<Eigen::Vector2d>& distorted) {
  if (distorted.empty()) return {};
  std::vector<cv::Point2d> in(distorted.size()), out;
  for (std::size_t i = 0; i < in.size(); ++i) in[i] = {distorted[i].x(), distorted[i].y()};
  cv::undistortPoints(
      in, out, cv::Matx33d::eye(), d.coefficients(), cv::noArray(), cv::noArray(),
      cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 200, 1e-12));
  std::vector<Eigen::Vector2d> result(out.size());
  for (std::size_t i = 0; i < out.size(); ++i) result[i] = {out[i].x, out[i].y};
  return result;
}

std::vector<double> parse_numbers(const std::string& text, char separator, std::size_t cap) {
  std::vector<double> numbers;
  std::istringstream in(text);
  std::string item;
  const auto next = [&] {
    return separator == ' ' ? static_cast<bool>(in >> item)
                            : static_cast<bool>(std::getline(in, item, separator));
  };
  while (numbers.size() < cap && next()) {
    char* end = nullptr;
    numbers.push_back(std::strtod(item.c_str(), &end));
    if (item.empty() || *end != '\0') numbers.back() = std::nan("");
  }
  return numbers;
}

LensDistortion parse_lens_distortion(const std::string& text) {
  return lens_distortion_from(parse_numbers(text, ',', 64), "distortion '" + text + "'");
}

LensDistortion lens_distortion_from_ros(const std::string& model, const std::vector<double>& d,
                                        const std::string& where) {
  if (std::all_of(d.begin(), d.end(), [](double v) { return v == 0; })) return {};
  const bool plumb_bob = model == "plumb_bob" && (d.size() == 4 || d.size() == 5);
  // rational_polynomial: k1 k2 p1 p2 k3 k4 k5 k6, the last three dividing the radial term.
  const bool rational_as_plumb_bob =
      model == "rational_polynomial" && d.size() == 8 && d[5] == 0 && d[6] == 0 && d[7] == 0;
  if (!plumb_bob && !rational_as_plumb_bob) {
    throw splat::Error(where + ": distortion model '" + model + "' with " +
                       std::to_string(d.size()) +
                       " coefficients is not supported (plumb_bob is): rectify the images first "
                       "(image_proc), or give --intrinsics fx,fy,cx,cy[,k1,k2,p1,p2,k3]");
  }
  return lens_distortion_from({d.begin(), d.begin() + std::min<std::size_t>(d.size(), 5)}, where);
}

struct Undistortion::Maps {
  cv::Mat x, y;  // raw pixel (OpenCV's convention: centres at whole numbers) of each pinhole pixel
};

namespace {

// Our cameras put pixel centres at +0.5, OpenCV's at whole numbers.
cv::Matx33d opencv_matrix(const splat::Camera& c) {
  return {c.fx, 0, c.cx - 0.5, 0, c.fy, c.cy - 0.5, 0, 0, 1};
}


// Whether the lens maps radii monotonically out to `reach` (normalized, distorted): past its peak
// a radial polynomial shows points nearer the axis again.
bool radially_monotonic(const LensDistortion& d, double reach) {
  double last = 0;
  for (double r = 1e-3; r < 10; r += 1e-3) {
    const double r2 = r * r, distorted = r * (1 + r2 * (d.k1 + r2 * (d.k2 + r2 * d.k3)));
    if (distorted <= last) return false;
    if (distorted >= reach) return true;
    last = distorted;
  }
  return false;
}

// How far, in pixels, the maps reach outside the raw pixels' centres (0: all inside).
double overshoot(const cv::Mat& map_x, const cv::Mat& map_y) {
  double worst = 0;
  for (int r = 0; r < map_x.rows; ++r) {
    for (int c = 0; c < map_x.cols; ++c) {
      const double x = map_x.at<float>(r, c), y = map_y.at<float>(r, c);
      if (!std::isfinite(x) || !std::isfinite(y)) return 1e9;
      worst = std::max({worst, -x, x - (map_x.cols - 1), -y, y - (map_x.rows - 1)});
    }
  }
  return worst;
}

// Depth at (x, y) in raw pixels (OpenCV's convention): interpolated where the four pixels around
// are measured and within kSmoothDepth of each other (one surface), else the nearest pixel's, so
// that no depth is made up across an object's edge or a hole's. Nearest everywhere would turn a
// slanted surface into steps of a duplicated row or column every few pixels.
constexpr float kSmoothDepth = 0.03f;  // relative; Kinect noise at 4 m is about 2%
void remap_depth(std::vector<float>& depth, int w, int h, const cv::Mat& map_x,
                 const cv::Mat& map_y) {
  if (depth.empty()) return;
  const std::vector<float> raw = depth;
  const auto at = [&](int x, int y) {
    return raw[static_cast<std::size_t>(std::clamp(y, 0, h - 1)) * w + std::clamp(x, 0, w - 1)];
  };
  for (int r = 0; r < h; ++r) {
    for (int c = 0; c < w; ++c) {
      const float x = map_x.at<float>(r, c), y = map_y.at<float>(r, c);
      const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
      const float fx = x - static_cast<float>(x0), fy = y - static_cast<float>(y0);
      const float d00 = at(x0, y0), d10 = at(x0 + 1, y0), d01 = at(x0, y0 + 1),
                  d11 = at(x0 + 1, y0 + 1);
      const float lo = std::min({d00, d10, d01, d11}), hi = std::max({d00, d10, d01, d11});
      float& out = depth[static_cast<std::size_t>(r) * w + c];
      if (lo > 0 && hi - lo <= kSmoothDepth * lo) {
        out = (d00 * (1 - fx) + d10 * fx) * (1 - fy) + (d01 * (1 - fx) + d11 * fx) * fy;
      } else {
        out = at(static_cast<int>(std::lround(x)), static_cast<int>(std::lround(y)));
      }
    }
  }
}

}  // namespace

Undistortion::Undistortion(const splat::Camera& raw, const LensDistortion& d,
                           const std::string& where)
    : raw_(raw), distortion_(d) {
  raw.validate(where);
  const cv::Size size(raw.width, raw.height);
  const cv::Matx33d K = opencv_matrix(raw);
  const std::vector<double> D = d.coefficients();
  // Out to the raw image's farthest edge: the pinhole view lies inside the edges, and a model
  // fitted without data in the corners (barrel lenses with k1 alone) may fold only there.
  const double reach = std::max(std::max(raw.cx, raw.width - raw.cx) / raw.fx,
                                std::max(raw.cy, raw.height - raw.cy) / raw.fy);
  bool usable = radially_monotonic(d, reach);
  auto maps = std::make_shared<Maps>();
  if (usable) {
    cv::Matx33d P = cv::getOptimalNewCameraMatrix(K, D, size, 0.0, size);
    // OpenCV finds the view on a coarse grid of the border: zoom in until no pixel looks past
    // the raw image's outer pixel centres (so none is made up by the border rule).
    bool inside = false;
    for (int step = 0; step < 50 && !inside; ++step) {
      cv::initUndistortRectifyMap(K, D, cv::noArray(), P, size, CV_32FC1, maps->x, maps->y);
      const double out = overshoot(maps->x, maps->y);
      inside = out <= 1e-3;
      const double zoom = 1 + (out + 0.01) / (0.5 * std::min(raw.width, raw.height));
      if (!inside) P(0, 0) *= zoom, P(1, 1) *= zoom;
    }
    usable = inside;
    pinhole_ = raw;
    pinhole_.fx = P(0, 0), pinhole_.fy = P(1, 1), pinhole_.cx = P(0, 2) + 0.5,
    pinhole_.cy = P(1, 2) + 0.5;
    // A lens keeps the view within a factor of two of its focal length.
    usable = usable && std::isfinite(pinhole_.fx) && std::isfinite(pinhole_.fy) &&
             pinhole_.fx > raw.fx / 2 && pinhole_.fx < raw.fx * 2 && pinhole_.fy > raw.fy / 2 &&
             pinhole_.fy < raw.fy * 2;
  }
  if (!usable) {
    throw splat::Error(
        where + ": distortion k1 " + std::to_string(d.k1) + ", k2 " + std::to_string(d.k2) +
        ", p1 " + std::to_string(d.p1) + ", p2 " + std::to_string(d.p2) + ", k3 " +
        std::to_string(d.k3) + " folds the " + std::to_string(raw.width) + "x" +
        std::to_string(raw.height) +
        " image over (no lens does): check the coefficients and their order k1,k2,p1,p2,k3");
  }
  pinhole_.validate(where);
  maps_ = std::move(maps);
}

void Undistortion::apply(splat::RgbdFrame& frame) const {
  const int w = pinhole_.width, h = pinhole_.height;
  if (frame.width() != w || frame.height() != h) {
    throw splat::Error("undistortion: frame is " + std::to_string(frame.width()) + "x" +
                       std::to_string(frame.height()) + ", the camera " + std::to_string(w) + "x" +
                       std::to_string(h));
  }
  remap_plane(frame.rgb, w, h, CV_32F, 3, maps_->x, maps_->y, cv::INTER_LINEAR);
  remap_depth(frame.depth, w, h, maps_->x, maps_->y);
  remap_plane(frame.ignore, w, h, CV_8U, 1, maps_->x, maps_->y, cv::INTER_NEAREST);
  remap_plane(frame.labels, w, h, CV_16U, 1, maps_->x, maps_->y, cv::INTER_NEAREST);
  frame.camera.fx = pinhole_.fx, frame.camera.fy = pinhole_.fy;
  frame.camera.cx = pinhole_.cx, frame.camera.cy = pinhole_.cy;
}

}  // namespace app
