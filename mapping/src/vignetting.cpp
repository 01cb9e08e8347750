#include "mapping/vignetting.h"

#include <string>

#include "splat/error.h"

namespace mapping {
namespace {

void check_size(const splat::Camera& camera, std::size_t values) {
  if (values != static_cast<std::size_t>(camera.width) * camera.height * 3) {
    throw splat::Error("Vignetting: image of " + std::to_string(values) + " values for a " + std::to_string(camera.width) +
                       "x" + std::to_string(camera.height) + " RGB camera");
  }
}

// Calls visit(pixel index, r^2) for every pixel of the camera's image.
template <typename Visit>
void for_each_pixel(const splat::Camera& camera, std::size_t values, Visit&& visit) {
  check_size(camera, values);
  for (int y = 0; y < camera.height; ++y) {
    const double v = (y + 0.5 - camera.cy) / camera.fy;
    for (int x = 0; x < camera.width; ++x) {
      const double u = (x + 0.5 - camera.cx) / camera.fx;
      visit(static_cast<std::size_t>(y) * camera.width + x, u * u + v * v);
    }
  }
}

}  // namespace

void Vignetting::apply(std::span<float> rgb, const splat::Camera& camera) const {
  check_size(camera, rgb.size());
  if (k1 == 0 && k2 == 0) return;
  for_each_pixel(camera, rgb.size(), [&](std::size_t p, double r2) {
    const float g = static_cast<float>(gain_at(r2));
    for (int c = 0; c < 3; ++c) rgb[p * 3 + c] *= g;
  });
}

std::array<double, 2> Vignetting::backward(std::span<const float> radiance, std::span<float> d_rgb,
                                           const splat::Camera& camera) const {
  if (radiance.size() != d_rgb.size()) throw splat::Error("Vignetting: radiance and gradient sizes differ");
  std::array<double, 2> d_k{0, 0};
  for_each_pixel(camera, d_rgb.size(), [&](std::size_t p, double r2) {
    const float g = static_cast<float>(gain_at(r2));
    double d_gain = 0;  // dL/d(gain) at this pixel
    for (int c = 0; c < 3; ++c) {
      d_gain += static_cast<double>(d_rgb[p * 3 + c]) * radiance[p * 3 + c];
      d_rgb[p * 3 + c] *= g;
    }
    d_k[0] += d_gain * r2;
    d_k[1] += d_gain * r2 * r2;
  });
  return d_k;
}

}  // namespace mapping
