#include "kernels/peak.h"

#include "kernels/dispatch.h"

namespace yelan::kernels {
namespace {

float fma_loop_scalar(std::int64_t iterations, float seed) {
  float a[8];
  for (int i = 0; i < 8; ++i) a[i] = seed + float(i);
  for (std::int64_t k = 0; k < iterations; ++k)
    for (int i = 0; i < 8; ++i) a[i] = a[i] * 0.9999999f + 1e-7f;
  float s = 0;
  for (float v : a) s += v;
  return s;
}

}  // namespace

const PeakKernels peak_scalar{Isa::scalar, 8 * 2, fma_loop_scalar};

YELAN_KERNEL_DISPATCH(PeakKernels, peak)

}  // namespace yelan::kernels
