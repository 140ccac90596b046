#include "kernels/loss.h"

#include <algorithm>
#include <cmath>

#include "kernels/dispatch.h"

namespace yelan::kernels {
namespace {

double bce_logits(const float* x, const float* t, std::size_t n, float* dx) {
  double sum = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double v = x[i];
    sum += std::max(v, 0.0) - v * t[i] + std::log1p(std::exp(-std::abs(v)));
    dx[i] = float(1.0 / (1.0 + std::exp(-v)) - t[i]);
  }
  return sum;
}

double jsd(const float* p, const float* q, std::size_t n, float eps, float* dp) {
  double sum = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double a = std::max(p[i], eps), b = std::max(q[i], eps), m = 0.5 * (a + b);
    sum += 0.5 * p[i] * std::log(a / m) + 0.5 * q[i] * std::log(b / m);
    dp[i] = float(0.5 * std::log(a / m));
  }
  return sum;
}

}  // namespace

const LossKernels loss_scalar{Isa::scalar, bce_logits, jsd};
YELAN_KERNEL_DISPATCH(LossKernels, loss)

}  // namespace yelan::kernels
