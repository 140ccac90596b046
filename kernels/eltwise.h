// Element-wise kernels over contiguous float arrays (any n, any alignment).
#pragma once
#include <cstddef>

#include "kernels/cpu.h"

namespace yelan::kernels {

struct EltwiseKernels {
  Isa isa;
  void (*add)(const float* a, const float* b, float* y, std::size_t n);     // y = a + b
  void (*axpy)(float alpha, const float* x, float* y, std::size_t n);       // y += alpha x
  void (*relu)(const float* x, float* y, std::size_t n);                    // y = max(x, 0)
  // dx = dy where x > 0, else 0 (x is the forward input)
  void (*relu_backward)(const float* x, const float* dy, float* dx, std::size_t n);
  float (*dot)(const float* a, const float* b, std::size_t n);
};

const EltwiseKernels& eltwise_kernels(Isa isa);
inline const EltwiseKernels& eltwise_kernels() { return eltwise_kernels(active_isa()); }

// The scalar reference every variant is tested against (dot accumulates in double).
extern const EltwiseKernels eltwise_scalar;

}  // namespace yelan::kernels
