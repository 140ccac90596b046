// FMA peak probe: 12 chains of 8-lane vectors.
#include <cstdint>

#include "kernels/peak.h"

#define PEAK_LANES 8
#define PEAK_CHAINS 12

namespace yelan::kernels {
namespace {
#include "kernels/peak_chains.inl"
}  // namespace

extern const PeakKernels peak_avx2{Isa::avx2, PEAK_CHAINS * PEAK_LANES * 2, fma_loop};

}  // namespace yelan::kernels
