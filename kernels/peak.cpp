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

#if defined(__x86_64__)
extern const PeakKernels peak_avx2;
extern const PeakKernels peak_avx512;
#elif defined(__aarch64__)
extern const PeakKernels peak_neon;
#endif

const PeakKernels& peak_kernels(Isa isa) {
  Variants<PeakKernels> v;
  v.scalar = &peak_scalar;
#if defined(__x86_64__)
  v.avx2 = &peak_avx2;
  v.avx512 = &peak_avx512;
#elif defined(__aarch64__)
  v.neon = &peak_neon;
#endif
  return select_variant(v, isa);
}

}  // namespace yelan::kernels
