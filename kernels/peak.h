// A probe of the machine's FMA throughput per ISA: independent FMA chains, enough of
// them to cover the FMA latency on every pipe, with no memory traffic. Benchmarks divide
// by what this measures in the same run, so their "% of peak" survives a noisy host.
#pragma once
#include <cstdint>

#include "kernels/cpu.h"

namespace yelan::kernels {

struct PeakKernels {
  Isa isa;
  int flops_per_iteration;  // FMAs per loop trip x lanes x 2
  float (*fma_loop)(std::int64_t iterations, float seed);
};

const PeakKernels& peak_kernels(Isa isa);

}  // namespace yelan::kernels
