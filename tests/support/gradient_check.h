#pragma once
#include <functional>
#include <span>
#include <string>
#include <vector>

namespace gslam::test {

struct GradientCheckOptions {
  // Central-difference step: truncation error ~h^2 stays below 1e-9 relative, while rounding
  // (~1e-16 per changed pixel / h) stays ~1e-11 absolute.
  double step = 1e-5;
  double rel_tol = 1e-5;  // max relative error where the gradient is not tiny
  // |gradient| below tiny * (largest in the group) is not compared: there the FD rounding noise
  // summed over the changed pixels (~1e-9) is no longer 1e-5 of the value.
  double tiny = 1e-6;
  // A mismatch is retried with the step divided by 8, this many times. A wrong gradient
  // disagrees at every step; a splat crossing the 1/255 alpha cut inside [-h, h] (a true
  // discontinuity of the model) only at steps larger than its distance to the cut.
  int retries = 3;
};

// The loss as terms whose sum it is (for example one per pixel). Differences are taken term by
// term before summing, so a loss summed over many pixels keeps its precision.
using LossTerms = std::function<std::vector<double>()>;

// Compares analytic[i] with the central difference of the loss along parameter i, where
// perturb(i, delta) adds delta to parameter i. Fails the test listing every mismatch
// (parameter name, index, numeric, analytic); returns the number of mismatches.
int expect_gradients_match(const std::string& name, std::span<const double> analytic,
                           const std::function<void(std::size_t, double)>& perturb,
                           const LossTerms& loss, const GradientCheckOptions& options = {});

}  // namespace gslam::test
