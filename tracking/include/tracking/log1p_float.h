// log(1 + x) for x >= 0 in float, in a few multiplies: the odometry's t-distribution cost takes
// one per residual, and glibc's double log1p there was 45% of tracking's time (docs/tuning.md).
#pragma once
#include <cmath>
#include <cstdint>
#include <cstring>

namespace tracking {

// Relative error under 4e-7 for every x >= 0; beyond float's comfortable range (1 + x >= 1e30),
// NaN and infinity, the library's log1p.
inline float log1p_nonnegative(float x) {
  const float y = 1.f + x;
  if (!(y < 1e30f)) return static_cast<float>(std::log1p(static_cast<double>(x)));
  std::uint32_t bits;
  std::memcpy(&bits, &y, sizeof bits);
  int exponent = static_cast<int>(bits >> 23) - 127;
  bits = (bits & 0x007FFFFFu) | 0x3F800000u;  // the mantissa m in [1, 2)
  float m;
  std::memcpy(&m, &bits, sizeof m);
  if (m > 1.41421356f) {
    m *= 0.5f;
    ++exponent;
  }
  // log m = 2 atanh(s), s = (m - 1) / (m + 1), |s| <= 0.172: the series to s^9 is exact in float.
  const float s = (m - 1.f) / (m + 1.f), s2 = s * s;
  const float log_m = 2.f * s * (1.f + s2 * (1.f / 3 + s2 * (1.f / 5 + s2 * (1.f / 7 + s2 * (1.f / 9)))));
  // (x - (y - 1)) / y restores what rounding 1 + x lost (tiny x).
  return static_cast<float>(exponent) * 0.693147180559945f + log_m + (x - (y - 1.f)) / y;
}

}  // namespace tracking
