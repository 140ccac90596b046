// Vector exp/log/sigmoid/tanh, 8 lanes.
#include <cstddef>

#include "kernels/vmath.h"

#define SIMD_VL 8

namespace yelan::kernels {
namespace {
#include "kernels/simd_types.inl"
#include "kernels/vmath_vec.inl"
#include "kernels/vmath_arrays.inl"
}  // namespace

extern const VmathKernels vmath_avx2{Isa::avx2, apply<vexp>, apply<vlog>, apply<vsigmoid>, apply<vtanh>};

}  // namespace yelan::kernels
