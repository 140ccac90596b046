// Element-wise TORE read-out kernels over a run of raw FIFO timestamps, one variant per
// ISA (tore_kernels.cpp: baseline; tore_kernels_simd.cpp, compiled once per ISA: the
// same source compiled with wider vectors). Chosen by kernels::active_isa().
#pragma once
#include <cstddef>
#include <cstdint>

#include "kernels/cpu.h"

namespace yelan::camera {

// Constants of one read-out, derived once per volume (tore.cpp).
struct ToreReadoutParams {
  std::int64_t t;          // read-out time (us)
  std::uint64_t horizon;   // YeLan: tau; Baldwin: max_t (both < 2^31)
  float offset, scale;     // YeLan: value = clamp(offset - scale * ln(1 + age), 0, 1)
                           // Baldwin: value = max(0, ln(1 + min(age, max_t)) - offset)
};

struct ToreKernels {
  kernels::Isa isa;
  void (*yelan)(const std::int64_t* stamps, std::size_t n, const ToreReadoutParams& p, float* out);
  void (*baldwin)(const std::int64_t* stamps, std::size_t n, const ToreReadoutParams& p, float* out);
};

const ToreKernels& tore_kernels(kernels::Isa isa);

}  // namespace yelan::camera
