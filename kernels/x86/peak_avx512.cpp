// FMA peak probe: 24 chains of 16-lane vectors.
#include <cstdint>

#include "kernels/peak.h"

#define PEAK_LANES 16
#define PEAK_CHAINS 24

namespace yelan::kernels {
namespace {
#include "kernels/peak_chains.inl"
}  // namespace

extern const PeakKernels peak_avx512{Isa::avx512, PEAK_CHAINS * PEAK_LANES * 2, fma_loop};

}  // namespace yelan::kernels
