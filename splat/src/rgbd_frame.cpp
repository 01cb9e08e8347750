#include "splat/rgbd_frame.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "splat/error.h"

namespace splat {

namespace {

// downsample's factor 2 (every level of the odometry's pyramids), unrolled: the same sums in the
// same order as the general loop, so the same result bit for bit, at a fraction of its time.
void halve(const RgbdFrame& f, RgbdFrame& out, float inv_area) {
  const int w = out.width(), h = out.height();
  const std::size_t in_w = static_cast<std::size_t>(f.width());
  for (int y = 0; y < h; ++y) {
    const std::size_t top = static_cast<std::size_t>(2 * y) * in_w, bottom = top + in_w;
    const float* rgb_top = f.rgb.data() + top * 3;
    const float* rgb_bottom = f.rgb.data() + bottom * 3;
    const float* depth_top = f.depth.data() + top;
    const float* depth_bottom = f.depth.data() + bottom;
    float* rgb_out = out.rgb.data() + static_cast<std::size_t>(y) * w * 3;
    float* depth_out = out.depth.data() + static_cast<std::size_t>(y) * w;
    for (int x = 0; x < w; ++x) {
      const int a = 2 * x, b = a + 1;
      for (int c = 0; c < 3; ++c) {
        rgb_out[3 * x + c] = (((rgb_top[3 * a + c] + rgb_top[3 * b + c]) + rgb_bottom[3 * a + c]) + rgb_bottom[3 * b + c]) * inv_area;
      }
      float depth = 0;
      int valid = 0;
      for (const float d : {depth_top[a], depth_top[b], depth_bottom[a], depth_bottom[b]}) {
        if (d > 0) depth += d, ++valid;
      }
      depth_out[x] = valid > 0 ? depth / static_cast<float>(valid) : 0.f;
    }
    if (!f.ignore.empty()) {
      for (int x = 0; x < w; ++x) {
        const std::size_t a = top + 2 * static_cast<std::size_t>(x), c = bottom + 2 * static_cast<std::size_t>(x);
        out.ignore[static_cast<std::size_t>(y) * w + x] =
            std::max({f.ignore[a], f.ignore[a + 1], f.ignore[c], f.ignore[c + 1]});
      }
    }
    if (!f.labels.empty()) {
      for (int x = 0; x < w; ++x) out.labels[static_cast<std::size_t>(y) * w + x] = f.labels[top + 2 * static_cast<std::size_t>(x)];
    }
  }
}

}  // namespace

RgbdFrame downsample(const RgbdFrame& f, int factor) {
  if (factor < 1) throw Error("downsample: factor is " + std::to_string(factor) + ", expected >= 1");
  const std::size_t pixels = static_cast<std::size_t>(f.width()) * f.height();
  if ((!f.ignore.empty() && f.ignore.size() != pixels) || (!f.labels.empty() && f.labels.size() != pixels)) {
    throw Error("downsample: the frame's ignore mask or labels do not match its " + std::to_string(f.width()) + "x" +
                std::to_string(f.height()) + " camera");
  }
  if (factor == 1) return f;
  RgbdFrame out;
  out.timestamp = f.timestamp;
  out.depth_time_offset = f.depth_time_offset;
  out.camera = f.camera;
  out.camera.width = f.width() / factor;
  out.camera.height = f.height() / factor;
  if (out.camera.width < 1 || out.camera.height < 1) throw Error("downsample: frame too small for factor " + std::to_string(factor));
  out.camera.fx /= factor;
  out.camera.fy /= factor;
  out.camera.cx /= factor;
  out.camera.cy /= factor;
  const int w = out.width(), h = out.height();
  out.rgb.assign(static_cast<std::size_t>(w) * h * 3, 0.f);
  out.depth.assign(static_cast<std::size_t>(w) * h, 0.f);
  const bool ignoring = !f.ignore.empty();
  if (ignoring) out.ignore.assign(static_cast<std::size_t>(w) * h, 0);
  if (!f.labels.empty()) out.labels.assign(static_cast<std::size_t>(w) * h, 0);
  const float inv_area = 1.f / static_cast<float>(factor * factor);
  if (factor == 2) {
    halve(f, out, inv_area);
    return out;
  }
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      float rgb[3] = {0, 0, 0}, depth = 0;
      int valid = 0;
      uint8_t ignored = 0;
      for (int dy = 0; dy < factor; ++dy) {
        for (int dx = 0; dx < factor; ++dx) {
          const std::size_t i = static_cast<std::size_t>(y * factor + dy) * f.width() + (x * factor + dx);
          for (int c = 0; c < 3; ++c) rgb[c] += f.rgb[i * 3 + c];
          if (ignoring) ignored = std::max(ignored, f.ignore[i]);
          if (f.depth[i] > 0) {
            depth += f.depth[i];
            ++valid;
          }
        }
      }
      const std::size_t o = static_cast<std::size_t>(y) * w + x;
      for (int c = 0; c < 3; ++c) out.rgb[o * 3 + c] = rgb[c] * inv_area;
      out.depth[o] = valid > 0 ? depth / static_cast<float>(valid) : 0.f;
      if (ignoring) out.ignore[o] = ignored;
      if (!f.labels.empty()) out.labels[o] = f.labels[static_cast<std::size_t>(y * factor) * f.width() + x * factor];
    }
  }
  return out;
}

Camera posed(const Camera& intrinsics, const Eigen::Isometry3d& T_cam_world) {
  Camera c = intrinsics;
  c.T_cam_world = T_cam_world;
  return c;
}

std::vector<float> reproject_depth(const std::vector<float>& depth, const Camera& c, const Eigen::Isometry3d& T_to_from) {
  const int w = c.width, h = c.height;
  if (depth.size() != static_cast<std::size_t>(w) * h) {
    throw Error("reproject_depth: " + std::to_string(depth.size()) + " depth values for a " + std::to_string(w) + "x" +
                std::to_string(h) + " camera");
  }
  std::vector<float> out(depth.size(), 0.f);
  const Eigen::Matrix3d R = T_to_from.linear();
  const Eigen::Vector3d t = T_to_from.translation();
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const double z = depth[static_cast<std::size_t>(y) * w + x];
      if (!(z > 0)) continue;
      const Eigen::Vector3d p = R * Eigen::Vector3d((x + 0.5 - c.cx) / c.fx * z, (y + 0.5 - c.cy) / c.fy * z, z) + t;
      if (!(p.z() > 0)) continue;
      const double u = c.fx * p.x() / p.z() + c.cx, v = c.fy * p.y() / p.z() + c.cy;
      if (!(u >= 0 && u < w && v >= 0 && v < h)) continue;
      float& target = out[static_cast<std::size_t>(v) * w + static_cast<std::size_t>(u)];
      const float moved = static_cast<float>(p.z());
      if (target == 0.f || moved < target) target = moved;
    }
  }
  return out;
}

void move_depth_to_colour_time(RgbdFrame& frame, const Eigen::Isometry3d& T_colour_depth) {
  frame.depth = reproject_depth(frame.depth, frame.camera, T_colour_depth);
  frame.depth_time_offset = 0;
}

}  // namespace splat
