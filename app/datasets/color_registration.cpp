#include "datasets/color_registration.h"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "datasets/lens_distortion.h"
#include "datasets/remap_plane.h"
#include "splat/error.h"

namespace app {

std::string ColorCamera::text() const {
  char out[160];
  std::snprintf(out, sizeof(out), "%.6g,%.6g,%.6g,%.6g", fx, fy, cx, cy);
  return out;
}

ColorCameraChoice parse_color_camera(const std::string& text) {
  ColorCameraChoice choice;
  if (text.empty() || text == "auto") return choice;
  if (text == kRegisteredColor) {
    choice.kind = ColorCameraChoice::kRegistered;
    return choice;
  }
  const std::vector<double> v = parse_numbers(text, ',', 5);
  const bool ok = v.size() == 4 && std::all_of(v.begin(), v.end(), [](double x) { return std::isfinite(x); }) &&
                  v[0] > 0 && v[1] > 0;
  if (!ok) {
    throw splat::Error("--color-camera '" + text +
                       "': expected auto, registered, or the colour camera's fx,fy,cx,cy (focal lengths > 0)");
  }
  choice.kind = ColorCameraChoice::kGiven;
  choice.given = {v[0], v[1], v[2], v[3]};
  return choice;
}

namespace {

// Where depth pixel (x, y) (centre at +0.5, as splat::Camera) falls in the colour image, in
// OpenCV's coordinates (centre at 0).
struct ColorMap {
  double sx, sy, ox, oy;  // colour x = sx * x + ox (OpenCV units), alike for y
  ColorMap(const splat::Camera& depth, const ColorCamera& color)
      : sx(color.fx / depth.fx), sy(color.fy / depth.fy), ox(color.cx - sx * depth.cx - 0.5),
        oy(color.cy - sy * depth.cy - 0.5) {}
  double x(double px) const { return sx * (px + 0.5) + ox; }
  double y(double py) const { return sy * (py + 0.5) + oy; }
};

}  // namespace

struct ColorResampler::Maps {
  cv::Mat x, y;                  // CV_32F, the depth image's size
  std::vector<uint8_t> outside;  // [H, W] 1 where the ray misses the colour image
  bool any_outside = false;
};

ColorResampler::ColorResampler(const splat::Camera& depth, const ColorCamera& color) : depth_(depth), color_(color) {
  auto maps = std::make_shared<Maps>();
  const int w = depth.width, h = depth.height;
  maps->x.create(h, w, CV_32F), maps->y.create(h, w, CV_32F);
  maps->outside.assign(static_cast<std::size_t>(w) * h, 0);
  const ColorMap m(depth, color);
  for (int py = 0; py < h; ++py) {
    for (int px = 0; px < w; ++px) {
      const double cx = m.x(px), cy = m.y(py);
      maps->x.at<float>(py, px) = static_cast<float>(cx), maps->y.at<float>(py, px) = static_cast<float>(cy);
      if (cx < -0.5 || cy < -0.5 || cx > w - 0.5 || cy > h - 0.5) {
        maps->outside[static_cast<std::size_t>(py) * w + px] = 1;
        maps->any_outside = true;
      }
    }
  }
  maps_ = std::move(maps);
}

void ColorResampler::apply(splat::RgbdFrame& frame) const {
  const int w = depth_.width, h = depth_.height;
  if (frame.width() != w || frame.height() != h || frame.rgb.size() != static_cast<std::size_t>(w) * h * 3) {
    throw splat::Error("colour registration: frame is " + std::to_string(frame.width()) + "x" +
                       std::to_string(frame.height()) + ", the camera " + std::to_string(w) + "x" + std::to_string(h));
  }
  remap_plane(frame.rgb, w, h, CV_32F, 3, maps_->x, maps_->y, cv::INTER_LINEAR);
  // Label images (and the dynamic classes' ignored pixels) belong to the colour image.
  remap_plane(frame.labels, w, h, CV_16U, 1, maps_->x, maps_->y, cv::INTER_NEAREST);
  remap_plane(frame.ignore, w, h, CV_8U, 1, maps_->x, maps_->y, cv::INTER_NEAREST);
  if (!maps_->any_outside) return;
  if (frame.ignore.empty()) frame.ignore.assign(maps_->outside.size(), 0);
  for (std::size_t i = 0; i < maps_->outside.size(); ++i) {
    frame.ignore[i] = std::max(frame.ignore[i], maps_->outside[i]);
  }
}

namespace {

// One frame's part of the edge score: its depth-edge pixels (centres, depth camera pixels) and
// its colour gradient magnitude blurred at two widths (coarse search, fine search).
struct EdgeFrame {
  std::vector<float> u, v;
  cv::Mat coarse, fine;  // CV_32F
};

// A depth discontinuity: the right or lower neighbour's depth differs by more than this fraction.
constexpr float kDepthJump = 0.05f;
constexpr std::size_t kMaxEdgesPerFrame = 1000;

EdgeFrame edge_frame(const splat::RgbdFrame& f, double unit) {
  EdgeFrame e;
  const int w = f.width(), h = f.height();
  std::vector<int> edges;
  for (int y = 0; y + 1 < h; ++y) {
    for (int x = 0; x + 1 < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      const float z = f.depth[i], zr = f.depth[i + 1], zd = f.depth[i + w];
      if (!(z > 0)) continue;
      if ((zr > 0 && std::abs(zr - z) > kDepthJump * z) || (zd > 0 && std::abs(zd - z) > kDepthJump * z)) {
        edges.push_back(static_cast<int>(i));
      }
    }
  }
  const std::size_t stride = std::max<std::size_t>(1, (edges.size() + kMaxEdgesPerFrame - 1) / kMaxEdgesPerFrame);
  for (std::size_t k = 0; k < edges.size(); k += stride) {
    e.u.push_back(static_cast<float>(edges[k] % w)), e.v.push_back(static_cast<float>(edges[k] / w));
  }
  cv::Mat gray(h, w, CV_32F);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const float* c = &f.rgb[(static_cast<std::size_t>(y) * w + x) * 3];
      gray.at<float>(y, x) = (c[0] + c[1] + c[2]) / 3.f;
    }
  }
  cv::GaussianBlur(gray, gray, cv::Size(0, 0), unit);
  cv::Mat gx, gy, magnitude;
  cv::Sobel(gray, gx, CV_32F, 1, 0);
  cv::Sobel(gray, gy, CV_32F, 0, 1);
  cv::magnitude(gx, gy, magnitude);
  cv::GaussianBlur(magnitude, e.coarse, cv::Size(0, 0), 4 * unit);  // a wide basin for the grid
  cv::GaussianBlur(magnitude, e.fine, cv::Size(0, 0), unit);
  return e;
}

float bilinear(const cv::Mat& m, double x, double y) {
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  if (x0 < 0 || y0 < 0 || x0 + 1 >= m.cols || y0 + 1 >= m.rows) return 0.f;
  const float ax = static_cast<float>(x - x0), ay = static_cast<float>(y - y0);
  const float* r0 = m.ptr<float>(y0) + x0;
  const float* r1 = m.ptr<float>(y0 + 1) + x0;
  return (1 - ay) * ((1 - ax) * r0[0] + ax * r0[1]) + ay * ((1 - ax) * r1[0] + ax * r1[1]);
}

// Mean gradient over the edge points (an edge mapped outside the colour image scores 0): every
// point on the narrow blur, every kCoarseStride-th on the wide one, where the grid is largest.
constexpr std::size_t kCoarseStride = 4;
double edge_score(const std::vector<EdgeFrame>& frames, bool fine, const splat::Camera& depth, const ColorCamera& c) {
  const ColorMap m(depth, c);
  const std::size_t stride = fine ? 1 : kCoarseStride;
  double sum = 0;
  std::size_t n = 0;
  for (const EdgeFrame& e : frames) {
    const cv::Mat& g = fine ? e.fine : e.coarse;
    for (std::size_t k = 0; k < e.u.size(); k += stride, ++n) sum += bilinear(g, m.x(e.u[k]), m.y(e.v[k]));
  }
  return n ? sum / static_cast<double>(n) : 0.0;
}

// The best camera on a grid around `centre`: focal ratios within +-ratio_span in ratio_steps
// each side, principal point shifts within +-px_span in px_steps each side.
ColorCamera search(const std::vector<EdgeFrame>& frames, bool fine, const splat::Camera& depth, const ColorCamera& centre,
                   double ratio_span, int ratio_steps, double px_span, int px_steps) {
  ColorCamera best = centre;
  double best_score = -1;
  for (int i = -ratio_steps; i <= ratio_steps; ++i) {
    const double ratio = centre.fx / depth.fx + ratio_span * i / ratio_steps;
    for (int j = -px_steps; j <= px_steps; ++j) {
      for (int k = -px_steps; k <= px_steps; ++k) {
        const ColorCamera c{ratio * depth.fx, ratio * depth.fy, centre.cx + px_span * j / px_steps,
                            centre.cy + px_span * k / px_steps};
        const double score = edge_score(frames, fine, depth, c);
        if (score > best_score) best_score = score, best = c;
      }
    }
  }
  return best;
}

}  // namespace

ColorCameraEstimate estimate_color_camera(std::span<const splat::RgbdFrame> frames) {
  ColorCameraEstimate out;
  if (frames.empty()) return out;
  const splat::Camera& depth = frames.front().camera;
  out.camera = {depth.fx, depth.fy, depth.cx, depth.cy};
  const double unit = depth.width / 640.0;  // the search's pixel sizes are a 640 px Kinect's
  std::vector<EdgeFrame> edges;
  for (const splat::RgbdFrame& f : frames) {
    if (f.width() != depth.width || f.height() != depth.height) {
      throw splat::Error("colour registration: frames of different sizes");
    }
    edges.push_back(edge_frame(f, unit));
    out.edge_points += edges.back().u.size();
  }
  if (out.edge_points < ColorCameraEstimate::kMinEdgePoints) return out;
  const ColorCamera registered = out.camera;
  // Ratios 0.8-1.25 in 0.01 steps, shifts +-20 px in 2 px steps, on the wide blur; then
  // +-0.015 / +-3 px and +-0.004 / +-0.8 px in quarters on the narrow one.
  const ColorCamera middle{1.025 * depth.fx, 1.025 * depth.fy, depth.cx, depth.cy};
  ColorCamera found = search(edges, false, depth, middle, 0.22, 22, 20 * unit, 10);
  found = search(edges, true, depth, found, 0.015, 4, 3 * unit, 4);
  found = search(edges, true, depth, found, 0.004, 4, 0.8 * unit, 4);
  const double registered_score = edge_score(edges, true, depth, registered);
  out.gain = registered_score > 0 ? edge_score(edges, true, depth, found) / registered_score : 1.0;
  if (out.gain >= ColorCameraEstimate::kMinGain) {
    out.camera = found;
    out.register_color = true;
  }
  return out;
}

}  // namespace app
