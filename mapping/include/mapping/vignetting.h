#pragma once
#include <array>
#include <span>

#include "splat/camera.h"

namespace mapping {

// The camera's radial fall-off of brightness (vignetting): the image records
// gain(r) * radiance with gain = 1 + k1 r^2 + k2 r^4, r the distance from the principal point
// in normalized image coordinates ((x - cx) / fx, (y - cy) / fy), so one model serves every
// resolution. A map fitted without it darkens each frame's centre and brightens its corners
// (teddy: the final map rendered 5% too dark at the centre, 7% too bright at the corners).
struct Vignetting {
  double k1 = 0, k2 = 0;

  double gain(double x_norm, double y_norm) const { return gain_at(x_norm * x_norm + y_norm * y_norm); }
  double gain_at(double r2) const { return 1 + r2 * (k1 + r2 * k2); }  // r2 = r^2
  // Multiplies an [H, W, 3] image (radiance) by the gain in place: what the camera records.
  void apply(std::span<float> rgb, const splat::Camera& camera) const;
  // Back through apply(): turns dL/d(recorded) into dL/d(radiance) in place, given the radiance,
  // and returns dL/d(k1, k2).
  std::array<double, 2> backward(std::span<const float> radiance, std::span<float> d_rgb, const splat::Camera& camera) const;
};

}  // namespace mapping
