// Vector exp/log/sigmoid/tanh, 4 lanes.
#include <cstddef>

#include "kernels/vmath.h"

#define SIMD_VL 4

namespace yelan::kernels {
namespace {
#include "kernels/simd_types.inl"
#include "kernels/vmath_vec.inl"
#include "kernels/vmath_arrays.inl"
}  // namespace

extern const VmathKernels vmath_neon{Isa::neon, apply<vexp>, apply<vlog>, apply<vsigmoid>, apply<vtanh>};

}  // namespace yelan::kernels
