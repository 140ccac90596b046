// The FMA-throughput probe of kernels/peak.h on native vectors.
#include <cstdint>

#include "kernels/peak.h"
#include "kernels/simd.h"

namespace yelan::kernels::YELAN_VARIANT_ISA {
namespace {

// The FMA-throughput loop: kChains independent accumulators of VL floats, enough chains to
// hide the FMA latency on every FMA pipe, few enough to stay in registers (AVX2 has 16 ymm).
constexpr int kChains = VL == 16 ? 24 : VL == 8 ? 12 : 24;

float fma_loop(std::int64_t iterations, float seed) {
  vf a[kChains];
  const vf m = vf{} + 0.9999999f, c = vf{} + 1e-7f;
  for (int i = 0; i < kChains; ++i) a[i] = vf{} + (seed + float(i));
  for (std::int64_t k = 0; k < iterations; ++k) {
#pragma GCC unroll 32
    for (int i = 0; i < kChains; ++i) a[i] = a[i] * m + c;
  }
  float s = 0;
  for (int i = 0; i < kChains; ++i)
    for (int l = 0; l < VL; ++l) s += a[i][l];
  return s;
}

constexpr PeakKernels kTable{Isa::YELAN_VARIANT_ISA, kChains * SIMD_VL * 2, fma_loop};

}  // namespace
}  // namespace yelan::kernels::YELAN_VARIANT_ISA

YELAN_EXPORT_KERNELS(PeakKernels, peak)
