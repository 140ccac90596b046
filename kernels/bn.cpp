#include "kernels/bn.h"

#include <cmath>
#include <vector>

#include "kernels/dispatch.h"

namespace yelan::kernels {
namespace {

constexpr int L = 16;

// Visits (channel, value index) of every element, plane by plane.
template <class F>
void each(const BnShape& s, F&& f) {
  for (int n = 0; n < s.n; ++n)
    for (int b = 0; b < s.cb; ++b) {
      const std::size_t base = (std::size_t(n) * s.cb + b) * s.pixels * L;
      for (std::size_t p = 0; p < s.pixels; ++p)
        for (int l = 0; l < L; ++l) f(b * L + l, base + p * L + l);
    }
}

void stats(const BnShape& s, const float* x, float* mean, float* var) {
  const int C = s.cb * L;
  std::vector<double> sum(C, 0.0), sq(C, 0.0);
  each(s, [&](int c, std::size_t i) { sum[c] += x[i]; });
  const double m = double(s.n) * s.pixels;
  for (int c = 0; c < C; ++c) mean[c] = float(sum[c] / m);
  each(s, [&](int c, std::size_t i) { sq[c] += (x[i] - sum[c] / m) * (x[i] - sum[c] / m); });
  for (int c = 0; c < C; ++c) var[c] = float(sq[c] / m);
}

void fwd(const BnShape& s, const float* x, const float* mean, const float* var, const float* gamma,
         const float* beta, float eps, bool relu, float* y) {
  each(s, [&](int c, std::size_t i) {
    float v = (x[i] - mean[c]) / std::sqrt(var[c] + eps) * gamma[c] + beta[c];
    y[i] = relu && v < 0.f ? 0.f : v;
  });
}

void bwd(const BnShape& s, const float* x, const float* y, const float* dy, const float* mean, const float* var,
         const float* gamma, float eps, bool relu, float* dx, float* dgamma, float* dbeta) {
  const int C = s.cb * L;
  std::vector<double> db(C, 0.0), dg(C, 0.0);
  auto g = [&](std::size_t i) { return relu && !(y[i] > 0.f) ? 0.0 : double(dy[i]); };
  each(s, [&](int c, std::size_t i) {
    db[c] += g(i);
    dg[c] += g(i) * (x[i] - mean[c]) / std::sqrt(double(var[c]) + eps);
  });
  const double m = double(s.n) * s.pixels;
  each(s, [&](int c, std::size_t i) {
    const double inv = 1.0 / std::sqrt(double(var[c]) + eps);
    const double xhat = (x[i] - mean[c]) * inv;
    dx[i] = float(gamma[c] * inv * (g(i) - db[c] / m - xhat * dg[c] / m));
  });
  for (int c = 0; c < C; ++c) {
    dgamma[c] = float(dg[c]);
    dbeta[c] = float(db[c]);
  }
}

}  // namespace

const BnKernels bn_scalar{Isa::scalar, stats, fwd, bwd};
YELAN_KERNEL_DISPATCH(BnKernels, bn)

}  // namespace yelan::kernels
