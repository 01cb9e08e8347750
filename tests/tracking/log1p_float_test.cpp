#include "tracking/log1p_float.h"

#include <cmath>
#include <limits>

#include <gtest/gtest.h>

namespace {

// Against the library's double log1p over every binade the odometry's costs reach (u / dof from
// 0 to far outliers), tiny arguments (where 1 + x rounds) and the edges.
TEST(Log1pFloat, MatchesTheLibraryToFloatPrecision) {
  double worst = 0;
  float worst_x = 0;
  for (int e = -40; e <= 100; ++e) {
    for (int k = 0; k < 997; ++k) {
      const float x = std::ldexp(1.f + static_cast<float>(k) / 997.f, e);
      const double exact = std::log1p(static_cast<double>(x));
      const double relative = std::abs(tracking::log1p_nonnegative(x) - exact) / exact;
      if (relative > worst) worst = relative, worst_x = x;
    }
  }
  EXPECT_LT(worst, 4e-7) << "at x = " << worst_x;
  EXPECT_EQ(tracking::log1p_nonnegative(0.f), 0.f);
  EXPECT_EQ(tracking::log1p_nonnegative(std::numeric_limits<float>::infinity()), std::numeric_limits<float>::infinity());
  EXPECT_TRUE(std::isnan(tracking::log1p_nonnegative(std::numeric_limits<float>::quiet_NaN())));
  EXPECT_NEAR(tracking::log1p_nonnegative(std::numeric_limits<float>::max()), std::log1p(double(std::numeric_limits<float>::max())), 1e-4);
}

}  // namespace
