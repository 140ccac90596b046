// Batch normalisation over the blocked layout, with an optional fused ReLU. A tensor is
// `planes` = N x CB planes of `pixels` = H x W pixels, 16 channel lanes each; per-channel
// arrays (mean, var, gamma, beta, their gradients) hold CB x 16 floats.
// Statistics are biased (divide by N x H x W), as PyTorch normalises in training.
#pragma once
#include <cstddef>

#include "kernels/cpu.h"

namespace yelan::kernels {

struct BnShape {
  int n = 1, cb = 1;           // batch, channel blocks
  std::size_t pixels = 1;      // H x W
};

struct BnKernels {
  Isa isa;
  void (*stats)(const BnShape& s, const float* x, float* mean, float* var);
  // y = (x - mean) / sqrt(var + eps) * gamma + beta, then max(y, 0) if relu. Training uses
  // the batch statistics, inference the running ones.
  void (*fwd)(const BnShape& s, const float* x, const float* mean, const float* var, const float* gamma,
              const float* beta, float eps, bool relu, float* y);
  // Training-mode backward through the batch statistics. y is the forward output (its
  // sign masks dy when relu). Overwrites dx, dgamma, dbeta.
  void (*bwd)(const BnShape& s, const float* x, const float* y, const float* dy, const float* mean,
              const float* var, const float* gamma, float eps, bool relu, float* dx, float* dgamma,
              float* dbeta);
};

const BnKernels& bn_kernels(Isa isa);
inline const BnKernels& bn_kernels() { return bn_kernels(active_isa()); }
extern const BnKernels bn_scalar;

}  // namespace yelan::kernels
