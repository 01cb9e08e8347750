#include "tracking/exposure_estimate.h"

#include <algorithm>
#include <cmath>

#include "splat/error.h"

namespace tracking {

namespace {
// Frames needed before the fit replaces the prior, and the spread of their nominal blur (pixels)
// without which the slope is not determined (a camera that has barely turned).
constexpr double kMinSamples = 30;
constexpr double kMinBlurSpread = 1.0;
// The fit takes frames of at most this nominal blur (pixels), where the fade grows linearly.
constexpr double kLinearBlur = 4.0;
// A sharpness outside this range is a frame without texture, not a measurement of blur.
constexpr double kMinSharpness = 0.05, kMaxSharpness = 20;
}  // namespace

double directional_sharpness(const OdometryFrame& frame, const Eigen::Vector2d& direction) {
  const OdometryFrame::Level& l = frame.levels().back();
  const float dx = static_cast<float>(direction.x()), dy = static_cast<float>(direction.y());
  double along = 0, across = 0;
  for (std::size_t i = 0; i < l.intensity_dx.size(); ++i) {
    const float gx = l.intensity_dx[i], gy = l.intensity_dy[i];
    const float a = gx * dx + gy * dy, c = gy * dx - gx * dy;
    along += a * a;
    across += c * c;
  }
  return across > 0 ? along / across : 1;
}

void ExposureEstimate::observe(const OdometryFrame& frame, const Eigen::Vector3d& angular_velocity) {
  if (!config_.estimate_exposure || !angular_velocity.allFinite() || frame.levels().empty()) return;
  // Turning about the camera's x and y axes moves the image centre along (w_y, -w_x); about z
  // (roll) it does not move it. Without motion the direction is arbitrary, and the frame still
  // tells the scene's anisotropy (the intercept).
  const Eigen::Vector2d flow(angular_velocity.y(), -angular_velocity.x());
  const double rate = flow.norm();
  const Eigen::Vector2d direction = rate > 1e-9 ? Eigen::Vector2d(flow / rate) : Eigen::Vector2d::UnitX();
  const double blur = frame.levels().back().fx * rate * config_.exposure;
  const double sharpness = std::clamp(directional_sharpness(frame, direction), kMinSharpness, kMaxSharpness);
  samples_.push_back({blur, 1 / sharpness});
  while (samples_.size() > static_cast<std::size_t>(config_.exposure_window)) samples_.pop_front();
}

double ExposureEstimate::exposure() const {
  if (!config_.estimate_exposure) return config_.exposure;
  // Least squares over the frames blurred little: further on the fade saturates (a frame smeared
  // by ten pixels is not much flatter along its motion than one smeared by five).
  double n = 0, sx = 0, sy = 0, lo = kLinearBlur, hi = 0;
  for (const auto& [x, y] : samples_) {
    if (x > kLinearBlur) continue;
    n += 1, sx += x, sy += y, lo = std::min(lo, x), hi = std::max(hi, x);
  }
  if (n < kMinSamples || hi - lo < kMinBlurSpread) return config_.exposure;
  const double mx = sx / n, my = sy / n;
  double sxx = 0, sxy = 0;
  for (const auto& [x, y] : samples_) {
    if (x <= kLinearBlur) sxx += (x - mx) * (x - mx), sxy += (x - mx) * (y - my);
  }
  const double slope = sxy / sxx, intercept = my - slope * mx;
  if (!(intercept > 0.1) || !std::isfinite(slope)) return config_.exposure;
  double residuals = 0;
  for (const auto& [x, y] : samples_) {
    if (x <= kLinearBlur) residuals += (y - intercept - slope * x) * (y - intercept - slope * x);
  }
  // The fit's standard error, relative to the intercept as the fade is: a fit that does not
  // pin the exposure down to half the prior's fade, or to half its own, leaves the prior.
  const double fade = slope / intercept, fade_error = std::sqrt(residuals / (n - 2) / sxx) / intercept;
  if (!(fade_error <= std::max(0.5 * config_.fade_per_blur_px, 0.5 * std::abs(fade)))) return config_.exposure;
  return config_.exposure * std::clamp(fade / config_.fade_per_blur_px, 0.25, 16.0);
}

void ExposureEstimate::restore(const std::vector<std::array<double, 2>>& samples) {
  if (samples.size() > static_cast<std::size_t>(config_.exposure_window)) {
    throw splat::Error("ExposureEstimate::restore: " + std::to_string(samples.size()) + " samples, the window holds " +
                       std::to_string(config_.exposure_window));
  }
  for (const auto& s : samples) {
    if (!std::isfinite(s[0]) || !std::isfinite(s[1])) throw splat::Error("ExposureEstimate::restore: a sample is not finite");
  }
  samples_.assign(samples.begin(), samples.end());
}

}  // namespace tracking
