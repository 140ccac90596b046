// Helpers shared by the tests: seeded random data, ISA loops, state guards.
#pragma once
#include <random>
#include <vector>

#include "camera/io/asan.h"
#include "kernels/cpu.h"

namespace yelan::test {

// A sanitizer build is there for memory errors and undefined behaviour: its long numeric
// sweeps may sample sparser, since the release run checks every sample.
inline constexpr bool kSanitized = kUnderAsan;

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

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "kernels/conv_bf16.h"

namespace yelan::test {

// The shared data folder (../shared/data beside the project, or $YELAN_SHARED_DATA) joined
// with `relative`. When it is absent (a user's clone) the test is reported SKIPPED: ctest
// runs each test case in its own process, and exit code 77 is its SKIP_RETURN_CODE.
inline std::string shared_data_or_skip(const std::string& relative) {
  std::string root;
  if (const char* env = std::getenv("YELAN_SHARED_DATA"); env && *env) root = env;
#ifdef YELAN_SHARED_DATA
  if (root.empty()) root = YELAN_SHARED_DATA;
#endif
  const std::string path = root + "/" + relative;
  if (root.empty() || !std::filesystem::exists(path)) {
    std::printf("SKIP: shared test data '%s' is not present\n", path.c_str());
    std::fflush(stdout);
    std::exit(77);
  }
  return path;
}

// Where the CPU or OS gives no AMX-BF16 (kernels/conv_bf16.h) the test is reported SKIPPED
// (exit 77, as above), naming what the CPU has.
inline void amx_or_skip() {
  if (yelan::kernels::amx_bf16_available()) return;
  std::printf("SKIP: no AMX-BF16 here (cpu: %s)\n", yelan::kernels::cpu_features().describe().c_str());
  std::fflush(stdout);
  std::exit(77);
}

// Where the CPU gives no AVX512-BF16, or the build no Winograd in bf16: SKIPPED (exit 77).
inline void winograd_bf16_or_skip() {
  if (yelan::kernels::winograd_bf16_available()) return;
  std::printf("SKIP: no AVX512-BF16 Winograd here (cpu: %s)\n", yelan::kernels::cpu_features().describe().c_str());
  std::fflush(stdout);
  std::exit(77);
}

}  // namespace yelan::test
