// Picks one family's kernel table for an ISA. A family that has no variant for an ISA
// falls back to the next one down (avx512 -> avx2 -> scalar, neon -> scalar), and the
// table's own `isa` field says which one actually runs.
#pragma once
#include "kernels/cpu.h"

namespace yelan::kernels {

template <class Table>
struct Variants {
  const Table* scalar = nullptr;
  const Table* avx2 = nullptr;
  const Table* avx512 = nullptr;
  const Table* neon = nullptr;
};

template <class Table>
const Table& select_variant(const Variants<Table>& v, Isa isa) {
  switch (isa) {
    case Isa::avx512: if (v.avx512) return *v.avx512; [[fallthrough]];
    case Isa::avx2: if (v.avx2) return *v.avx2; break;
    case Isa::neon: if (v.neon) return *v.neon; break;
    case Isa::scalar: break;
  }
  return *v.scalar;
}

}  // namespace yelan::kernels

// Defines `const Table& <family>_kernels(Isa)` over the scalar table `<family>_scalar` and
// the ISA variants `<family>_avx2`, `<family>_avx512` (x86-64) or `<family>_neon` (aarch64)
// that <family>_simd.cpp defines per ISA (YELAN_VARIANT in variant.h). Usable in any namespace.
#if defined(__x86_64__)
#define YELAN_KERNEL_DISPATCH(Table, family)                                                       \
  extern const Table family##_avx2;                                                                \
  extern const Table family##_avx512;                                                              \
  const Table& family##_kernels(::yelan::kernels::Isa isa) {                                       \
    return ::yelan::kernels::select_variant(                                                       \
        ::yelan::kernels::Variants<Table>{&family##_scalar, &family##_avx2, &family##_avx512, nullptr}, isa); \
  }
#elif defined(__aarch64__)
#define YELAN_KERNEL_DISPATCH(Table, family)                                                       \
  extern const Table family##_neon;                                                                \
  const Table& family##_kernels(::yelan::kernels::Isa isa) {                                       \
    return ::yelan::kernels::select_variant(                                                       \
        ::yelan::kernels::Variants<Table>{&family##_scalar, nullptr, nullptr, &family##_neon}, isa); \
  }
#else
#define YELAN_KERNEL_DISPATCH(Table, family)                                                       \
  const Table& family##_kernels(::yelan::kernels::Isa isa) {                                       \
    return ::yelan::kernels::select_variant(::yelan::kernels::Variants<Table>{&family##_scalar}, isa); \
  }
#endif
