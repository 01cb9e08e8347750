// The CPU backend's per-lane arithmetic (splat/src/cpu): the vectorized exp every pass
// evaluates alpha with, and the row helpers, lane by lane against the scalar forms.
#include <cmath>

#include <gtest/gtest.h>

#include "cpu/composite_common.h"

namespace {

using splat::cpu::Row;

TEST(Lanes, FloatExpIsWithinThreeUlpOfTheExactValueDownToTheFlushLimit) {
  double worst = 0, worst_at = 0;
  for (int i = 0; i <= 2000000; ++i) {
    const float x = static_cast<float>(-87.0 * i / 2000000);
    const double exact = std::exp(static_cast<double>(x));
    const double error = std::abs(splat::cpu::exp_nonpositive(x) - exact) / exact;
    if (error > worst) worst = error, worst_at = x;
  }
  std::printf("largest relative error %.3g (%.2f ulp) at x = %.6f\n", worst, worst / 0x1p-24, worst_at);
  EXPECT_LT(worst, 3 * 0x1p-24);
  EXPECT_EQ(splat::cpu::exp_nonpositive(0.f), 1.f);
  EXPECT_GT(splat::cpu::exp_nonpositive(1e-6f), 1.f);  // a rounding-negative sigma stays finite
}

TEST(Lanes, RowsGiveTheScalarResultInEveryLane) {
  Row<float> x;
  for (int k = 0; k < splat::cpu::kRowLanes; ++k) x[k] = -0.37f * static_cast<float>(k * k) - 0.5f * static_cast<float>(k % 3);
  const Row<float> e = splat::cpu::exp_nonpositive(x), f = splat::cpu::floor_lanes(x),
                   m = splat::cpu::max_lanes(x, -20.f), r = splat::cpu::round_lanes(x);
  for (int k = 0; k < splat::cpu::kRowLanes; ++k) {
    EXPECT_EQ(e[k], splat::cpu::exp_nonpositive(x[k])) << "lane " << k;
    EXPECT_EQ(f[k], std::floor(x[k])) << "lane " << k;
    EXPECT_EQ(m[k], std::max(x[k], -20.f)) << "lane " << k;
    EXPECT_LE(std::abs(r[k] - x[k]), 0.5f) << "lane " << k;
    EXPECT_EQ(r[k], std::floor(r[k])) << "lane " << k;
  }
}

}  // namespace
