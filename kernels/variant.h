// What an ISA variant source sees (kernels/<family>_simd.cpp, camera/repr/tore_kernels_simd.cpp):
// the build compiles each such file once per ISA of the target (kernels/isa_variants.cmake)
// with YELAN_VARIANT_ISA (avx2, avx512 or neon) and SIMD_VL (floats per native vector)
// defined and that ISA's flags. Its code goes in namespace yelan::kernels::YELAN_VARIANT_ISA,
// inside an anonymous namespace: a profile names the ISA (yelan::kernels::avx512::...), and
// nothing compiled with wide vectors can be merged by the linker into baseline code.
#pragma once
#if !defined(YELAN_VARIANT_ISA) || !defined(SIMD_VL)
#error "an ISA variant source: compile it through yelan_isa_variants() (kernels/isa_variants.cmake)"
#endif

#define YELAN_VARIANT_PASTE_(a, b) a##_##b
#define YELAN_VARIANT_PASTE(a, b) YELAN_VARIANT_PASTE_(a, b)
// The name of a family's table in this build: YELAN_VARIANT(conv) is conv_avx512 when
// compiled for avx512; dispatch.h declares and picks them.
#define YELAN_VARIANT(family) YELAN_VARIANT_PASTE(family, YELAN_VARIANT_ISA)

// Ends a kernels/<family>_simd.cpp: its table, `kTable` in the ISA's namespace, becomes
// <family>_<isa> in yelan::kernels.
#define YELAN_EXPORT_KERNELS(Table, family) \
  namespace yelan::kernels {                \
  extern const Table YELAN_VARIANT(family) = YELAN_VARIANT_ISA::kTable; \
  }
