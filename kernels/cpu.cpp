#include "kernels/cpu.h"

#include <atomic>
#include <cstdlib>
#include <mutex>
#include <stdexcept>

#if defined(__x86_64__) || defined(_M_X64)
#include <cpuid.h>
#define YELAN_X86 1
#elif defined(__aarch64__)
#include <sys/auxv.h>
#include <asm/hwcap.h>
#define YELAN_ARM 1
#endif

namespace yelan::kernels {
namespace {

#if YELAN_X86
unsigned long long read_xcr0() {
  unsigned eax, edx;
  __asm__ volatile("xgetbv" : "=a"(eax), "=d"(edx) : "c"(0));
  return (static_cast<unsigned long long>(edx) << 32) | eax;
}

CpuFeatures detect() {
  CpuFeatures f;
  unsigned a, b, c, d;
  if (!__get_cpuid(1, &a, &b, &c, &d)) return f;
  f.sse42 = c & bit_SSE4_2;
  const bool osxsave = c & bit_OSXSAVE;
  const bool cpu_avx = c & bit_AVX, cpu_fma = c & bit_FMA, cpu_f16c = c & bit_F16C;
  const unsigned long long xcr0 = osxsave ? read_xcr0() : 0;
  const bool os_ymm = (xcr0 & 0x6) == 0x6;     // SSE and AVX state
  const bool os_zmm = (xcr0 & 0xE6) == 0xE6;   // plus opmask and both ZMM halves
  f.avx = cpu_avx && os_ymm;
  f.fma = cpu_fma && os_ymm;
  f.f16c = cpu_f16c && os_ymm;
  if (__get_cpuid_count(7, 0, &a, &b, &c, &d)) {
    f.avx2 = (b & bit_AVX2) && os_ymm;
    f.avx512f = (b & bit_AVX512F) && os_zmm;
    f.avx512bw = (b & bit_AVX512BW) && os_zmm;
    f.avx512vl = (b & bit_AVX512VL) && os_zmm;
    f.avx512dq = (b & bit_AVX512DQ) && os_zmm;
    const bool os_tiles = (xcr0 & 0x60000) == 0x60000;  // XTILECFG and XTILEDATA
    f.amx_tile = (d & (1u << 24)) && os_tiles;
    f.amx_bf16 = (d & (1u << 22)) && os_tiles;
    unsigned a1, b1, c1, d1;
    if (a >= 1 && __get_cpuid_count(7, 1, &a1, &b1, &c1, &d1)) f.avx512bf16 = (a1 & (1u << 5)) && os_zmm;
  }
  return f;
}
#elif YELAN_ARM
CpuFeatures detect() {
  CpuFeatures f;
  const unsigned long hw = getauxval(AT_HWCAP);
  f.neon = hw & HWCAP_ASIMD;
  f.fp16 = hw & HWCAP_FPHP;
  f.dotprod = hw & HWCAP_ASIMDDP;
  return f;
}
#else
CpuFeatures detect() { return {}; }
#endif

std::atomic<int> g_isa{-1};
std::once_flag g_env_once;

bool compiled_in(Isa isa) {
  switch (isa) {
    case Isa::scalar: return true;
#if YELAN_X86
    case Isa::avx2:
    case Isa::avx512: return true;
#endif
#if YELAN_ARM
    case Isa::neon: return true;
#endif
    default: return false;
  }
}

}  // namespace

std::string CpuFeatures::describe() const {
  std::string s;
  auto add = [&](bool on, const char* name) {
    if (!on) return;
    if (!s.empty()) s += ' ';
    s += name;
  };
  add(sse42, "sse4.2"); add(avx, "avx"); add(avx2, "avx2"); add(fma, "fma"); add(f16c, "f16c");
  add(avx512f, "avx512f"); add(avx512bw, "avx512bw"); add(avx512vl, "avx512vl");
  add(avx512dq, "avx512dq"); add(avx512bf16, "avx512bf16"); add(amx_tile, "amx-tile"); add(amx_bf16, "amx-bf16"); add(neon, "neon"); add(fp16, "fp16"); add(dotprod, "dotprod");
  return s.empty() ? "none" : s;
}

const CpuFeatures& cpu_features() {
  static const CpuFeatures f = detect();
  return f;
}

const char* isa_name(Isa isa) {
  switch (isa) {
    case Isa::scalar: return "scalar";
    case Isa::avx2: return "avx2";
    case Isa::avx512: return "avx512";
    case Isa::neon: return "neon";
  }
  return "?";
}

std::optional<Isa> parse_isa(std::string_view name) {
  for (Isa isa : {Isa::scalar, Isa::avx2, Isa::avx512, Isa::neon})
    if (name == isa_name(isa)) return isa;
  return std::nullopt;
}

bool isa_supported(Isa isa) {
  if (!compiled_in(isa)) return false;
  const CpuFeatures& f = cpu_features();
  switch (isa) {
    case Isa::scalar: return true;
    case Isa::avx2: return f.avx2 && f.fma;
    case Isa::avx512: return f.avx512f && f.avx512bw && f.avx512vl && f.avx512dq && f.fma;
    case Isa::neon: return f.neon;
  }
  return false;
}

Isa best_isa() {
  for (Isa isa : {Isa::avx512, Isa::avx2, Isa::neon})
    if (isa_supported(isa)) return isa;
  return Isa::scalar;
}

std::string supported_isas() {
  std::string s;
  for (Isa isa : {Isa::scalar, Isa::avx2, Isa::avx512, Isa::neon})
    if (isa_supported(isa)) s += s.empty() ? isa_name(isa) : std::string(" ") + isa_name(isa);
  return s;
}

void set_isa(Isa isa) {
  if (!isa_supported(isa))
    throw std::invalid_argument(std::string("ISA '") + isa_name(isa) +
                                "' is not supported here (available: " + supported_isas() + ")");
  g_isa.store(static_cast<int>(isa));
}

Isa active_isa() {
  int v = g_isa.load();
  if (v >= 0) return static_cast<Isa>(v);
  std::call_once(g_env_once, [] {
    if (g_isa.load() >= 0) return;
    const char* env = std::getenv("YELAN_ISA");
    if (!env || !*env) {
      g_isa.store(static_cast<int>(best_isa()));
      return;
    }
    auto isa = parse_isa(env);
    if (!isa)
      throw std::invalid_argument(std::string("YELAN_ISA='") + env +
                                  "' is not one of scalar, avx2, avx512, neon");
    set_isa(*isa);
  });
  v = g_isa.load();
  return static_cast<Isa>(v);
}

}  // namespace yelan::kernels
