// Element-wise exp, log, sigmoid, tanh over arrays. The scalar table calls the C library
// (the reference); SIMD variants use the vector math of kernels/simd.h, whose error bounds are stated
// there and measured by tests/kernels/test_vmath.cpp.
#pragma once
#include <cstddef>

#include "kernels/cpu.h"

namespace yelan::kernels {

struct VmathKernels {
  Isa isa;
  void (*exp)(const float* x, float* y, std::size_t n);
  void (*log)(const float* x, float* y, std::size_t n);
  void (*sigmoid)(const float* x, float* y, std::size_t n);
  void (*tanh)(const float* x, float* y, std::size_t n);
};

const VmathKernels& vmath_kernels(Isa isa);
inline const VmathKernels& vmath_kernels() { return vmath_kernels(active_isa()); }
extern const VmathKernels vmath_scalar;

}  // namespace yelan::kernels
