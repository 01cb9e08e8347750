#pragma once
#include <cmath>

namespace splat {

struct AdamHyper {
  double beta1 = 0.9, beta2 = 0.999;
  double eps = 1e-15;  // as 3DGS: tiny, so small gradients still move parameters
};

// One Adam update of one value. `bias1` and `bias2` are 1 - beta^t for its step count t >= 1.
template <typename T>
inline void adam_update(T& param, T grad, T& m, T& v, double lr, double bias1, double bias2,
                        const AdamHyper& h) {
  m = static_cast<T>(h.beta1 * m + (1 - h.beta1) * grad);
  v = static_cast<T>(h.beta2 * v + (1 - h.beta2) * double(grad) * grad);
  param -= static_cast<T>(lr * (m / bias1) / (std::sqrt(v / bias2) + h.eps));
}

}  // namespace splat
