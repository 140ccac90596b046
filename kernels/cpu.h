// CPU feature detection and the choice of kernel ISA, made once at run time.
#pragma once
#include <optional>
#include <string>
#include <string_view>

namespace yelan::kernels {

enum class Isa { scalar, avx2, avx512, neon };

struct CpuFeatures {
  // x86: each flag means the CPU has it AND the OS saves the registers it needs.
  bool sse42 = false, avx = false, avx2 = false, fma = false, f16c = false;
  bool avx512f = false, avx512bw = false, avx512vl = false, avx512dq = false;
  bool avx512bf16 = false, amx_tile = false, amx_bf16 = false;  // amx: CPU and OS tile state
  // aarch64
  bool neon = false, fp16 = false, dotprod = false;
  std::string describe() const;  // e.g. "avx2 fma f16c avx512f avx512bw ..."
};

const CpuFeatures& cpu_features();

const char* isa_name(Isa isa);
std::optional<Isa> parse_isa(std::string_view name);  // "scalar", "avx2", "avx512", "neon"
bool isa_supported(Isa isa);                           // by this CPU and this build
Isa best_isa();

// The ISA every kernel family dispatches to. First use reads YELAN_ISA; an unknown or
// unsupported value throws std::invalid_argument naming the value and what is available.
Isa active_isa();
// Forces the ISA (tests, benchmarks, --isa). Throws std::invalid_argument if unsupported.
void set_isa(Isa isa);
// "scalar avx2 avx512": every ISA this machine can run.
std::string supported_isas();

}  // namespace yelan::kernels
