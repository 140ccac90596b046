// exp, log, sigmoid and tanh over arrays, on the vector math of kernels/simd.h.
#include <cstddef>

#include "kernels/vmath.h"
#include "kernels/simd.h"

namespace yelan::kernels::YELAN_VARIANT_ISA {
namespace {

// The tail goes through a zero-padded vector, so every element gets the same formula.
template <vf (*F)(vf)>
void apply(const float* x, float* y, std::size_t n) {
  std::size_t i = 0;
  for (; i + VL <= n; i += VL) storef(y + i, F(loadf(x + i)));
  if (i < n) {
    float in[VL] = {}, out[VL];
    for (std::size_t k = 0; i + k < n; ++k) in[k] = x[i + k];
    storef(out, F(loadf(in)));
    for (std::size_t k = 0; i + k < n; ++k) y[i + k] = out[k];
  }
}

constexpr VmathKernels kTable{Isa::YELAN_VARIANT_ISA, apply<vexp>, apply<vlog>, apply<vsigmoid>, apply<vtanh>};

}  // namespace
}  // namespace yelan::kernels::YELAN_VARIANT_ISA

YELAN_EXPORT_KERNELS(VmathKernels, vmath)
