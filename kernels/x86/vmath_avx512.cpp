// Vector exp/log/sigmoid/tanh, 16 lanes.
#include <cstddef>

#include "kernels/vmath.h"

#define SIMD_VL 16

namespace yelan::kernels {
namespace {
#include "kernels/simd_types.inl"
#include "kernels/vmath_vec.inl"
#include "kernels/vmath_arrays.inl"
}  // namespace

extern const VmathKernels vmath_avx512{Isa::avx512, apply<vexp>, apply<vlog>, apply<vsigmoid>, apply<vtanh>};

}  // namespace yelan::kernels
