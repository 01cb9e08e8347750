#include "support/gradient_check.h"

#include <algorithm>
#include <cmath>
#include <sstream>

#include <gtest/gtest.h>

namespace gslam::test {
namespace {

// The five-point central difference (f(-2h) - 8 f(-h) + 8 f(h) - f(2h)) / 12h: its truncation
// error is ~h^4, so the step can be large enough that rounding in the loss stays far below
// 1e-5 of even small gradients.
double central_difference(std::size_t i, double step,
                          const std::function<void(std::size_t, double)>& perturb,
                          const LossTerms& loss) {
  auto loss_at = [&](double offset) {
    perturb(i, offset);
    std::vector<double> terms = loss();
    perturb(i, -offset);
    return terms;
  };
  const std::vector<double> far_minus = loss_at(-2 * step), minus = loss_at(-step), plus = loss_at(step),
                            far_plus = loss_at(2 * step);
  double sum = 0;
  for (std::size_t k = 0; k < plus.size(); ++k) sum += 8 * (plus[k] - minus[k]) - (far_plus[k] - far_minus[k]);
  return sum / (12 * step);
}

bool close(double numeric, double analytic, double floor, double rel_tol) {
  const double scale = std::max(std::abs(numeric), std::abs(analytic));
  return scale <= floor || std::abs(numeric - analytic) <= rel_tol * scale;
}

}  // namespace

int expect_gradients_match(const std::string& name, std::span<const double> analytic,
                           const std::function<void(std::size_t, double)>& perturb,
                           const LossTerms& loss, const GradientCheckOptions& options) {
  std::vector<double> numeric(analytic.size());
  double largest = 0;
  for (std::size_t i = 0; i < analytic.size(); ++i) {
    numeric[i] = central_difference(i, options.step, perturb, loss);
    largest = std::max({largest, std::abs(numeric[i]), std::abs(analytic[i])});
  }
  const double floor = options.tiny * largest;
  std::ostringstream report;
  int mismatches = 0;
  for (std::size_t i = 0; i < analytic.size(); ++i) {
    double step = options.step;
    for (int retry = 0; retry < options.retries &&
                        !close(numeric[i], analytic[i], floor, options.rel_tol);
         ++retry) {
      step /= 8;
      numeric[i] = central_difference(i, step, perturb, loss);
    }
    if (!close(numeric[i], analytic[i], floor, options.rel_tol)) {
      ++mismatches;
      report << "  " << name << "[" << i << "]: numeric " << numeric[i] << ", analytic "
             << analytic[i] << ", relative error "
             << std::abs(numeric[i] - analytic[i]) /
                    std::max(std::abs(numeric[i]), std::abs(analytic[i]))
             << "\n";
    }
  }
  EXPECT_EQ(mismatches, 0) << name << ": " << mismatches << " of " << analytic.size()
                           << " gradients differ from central differences:\n"
                           << report.str();
  EXPECT_GT(largest, 0) << name << ": every gradient is zero, the check proves nothing";
  return mismatches;
}

}  // namespace gslam::test
