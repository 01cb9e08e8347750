#include "splat/rgbd_frame.h"

#include <string>

#include "splat/error.h"

namespace splat {

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

}  // namespace splat
