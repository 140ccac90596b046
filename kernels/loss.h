// Loss kernels over flat arrays. Each returns the SUM of the per-element losses (in
// double) and writes the gradient of that sum; layers divide by their counts.
#pragma once
#include <cstddef>

#include "kernels/cpu.h"

namespace yelan::kernels {

struct LossKernels {
  Isa isa;
  // Binary cross-entropy on logits x with targets t in [0, 1]:
  //   max(x, 0) - x t + log(1 + exp(-|x|));  dx = sigmoid(x) - t
  double (*bce_logits)(const float* x, const float* t, std::size_t n, float* dx);
  // Jensen-Shannon divergence of distribution p from q, m = (p + q) / 2:
  //   sum 0.5 p log(p / m) + 0.5 q log(q / m);  dp = 0.5 log(p / m)
  // p and q are clamped to >= eps inside the logarithms (an empty bin costs nothing).
  double (*jsd)(const float* p, const float* q, std::size_t n, float eps, float* dp);
};

const LossKernels& loss_kernels(Isa isa);
inline const LossKernels& loss_kernels() { return loss_kernels(active_isa()); }
extern const LossKernels loss_scalar;

}  // namespace yelan::kernels
