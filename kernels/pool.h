// Pooling over the blocked layout: `planes` = N x CB planes of H x W pixels x 16 lanes.
// Max pooling pads with -inf (padding never wins) and records, per output element, the
// input pixel it took, so the backward pass is a scatter of dy to those pixels.
#pragma once
#include <cstddef>
#include <cstdint>

#include "kernels/cpu.h"

namespace yelan::kernels {

struct PoolShape {
  int planes = 1, ih = 1, iw = 1, k = 1, stride = 1, pad = 0;
  int oh() const { return (ih + 2 * pad - k) / stride + 1; }
  int ow() const { return (iw + 2 * pad - k) / stride + 1; }
  bool valid() const {
    return planes > 0 && ih > 0 && iw > 0 && k > 0 && stride > 0 && pad >= 0 && 2 * pad <= k &&
           ih + 2 * pad >= k && iw + 2 * pad >= k;
  }
};

struct PoolKernels {
  Isa isa;
  // argmax: one int32 per output element (the input pixel index h * iw + w)
  void (*max_fwd)(const PoolShape& s, const float* x, float* y, std::int32_t* argmax);
  void (*max_bwd)(const PoolShape& s, const float* dy, const std::int32_t* argmax, float* dx);  // overwrites dx
  // mean over all pixels of each plane: y has planes x 16 floats
  void (*avg_global_fwd)(int planes, std::size_t pixels, const float* x, float* y);
  void (*avg_global_bwd)(int planes, std::size_t pixels, const float* dy, float* dx);
};

const PoolKernels& pool_kernels(Isa isa);
inline const PoolKernels& pool_kernels() { return pool_kernels(active_isa()); }
extern const PoolKernels pool_scalar;

}  // namespace yelan::kernels
