#include "kernels/vmath.h"

#include <cmath>

#include "kernels/dispatch.h"

namespace yelan::kernels {
namespace {

template <float (*F)(float)>
void apply(const float* x, float* y, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) y[i] = F(x[i]);
}
float exp_ref(float v) { return std::exp(v); }
float log_ref(float v) { return std::log(v); }
float sigmoid_ref(float v) { return float(1.0 / (1.0 + std::exp(-double(v)))); }
float tanh_ref(float v) { return std::tanh(v); }

}  // namespace

const VmathKernels vmath_scalar{Isa::scalar, apply<exp_ref>, apply<log_ref>, apply<sigmoid_ref>,
                                apply<tanh_ref>};

YELAN_KERNEL_DISPATCH(VmathKernels, vmath)

}  // namespace yelan::kernels
