// Helpers shared by the tests: seeded random data, ISA loops, state guards.
#pragma once
#include <random>
#include <vector>

#include "kernels/cpu.h"

namespace yelan::test {

inline std::vector<float> random_floats(std::size_t n, unsigned seed, float lo = -1.f, float hi = 1.f) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(lo, hi);
  std::vector<float> v(n);
  for (auto& x : v) x = u(rng);
  return v;
}

inline std::vector<kernels::Isa> supported_isas() {
  std::vector<kernels::Isa> out;
  for (auto isa : {kernels::Isa::scalar, kernels::Isa::avx2, kernels::Isa::avx512, kernels::Isa::neon})
    if (kernels::isa_supported(isa)) out.push_back(isa);
  return out;
}

// Restores the active ISA when a test that forces one ends.
struct IsaGuard {
  kernels::Isa saved = kernels::active_isa();
  ~IsaGuard() { kernels::set_isa(saved); }
};

}  // namespace yelan::test
