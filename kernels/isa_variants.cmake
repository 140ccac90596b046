# The one place ISA flags are written. An ISA variant source (kernels/<family>_simd.cpp,
# camera/repr/tore_kernels_simd.cpp) is compiled once per ISA the target architecture
# dispatches to, with that ISA's flags and YELAN_VARIANT_ISA / SIMD_VL defined (see
# kernels/variant.h); everything else stays baseline x86-64 or armv8-a and runs on any CPU.
#   yelan_isa_variants(TARGET SOURCES file... [OPTIONS flag...])
if(YELAN_ARCH STREQUAL "x86_64")
  set(YELAN_VARIANT_ISAS "avx2:8" "avx512:16")
elseif(YELAN_ARCH STREQUAL "aarch64")
  set(YELAN_VARIANT_ISAS "neon:4")
else()
  set(YELAN_VARIANT_ISAS "")  # scalar only
endif()
# -Wno-psabi: wide vectors never cross a call boundary (file-local, inlined). GCC 12 warns
# about uninitialised variables inside its own avx512fintrin.h (masked intrinsics with an
# undefined pass-through operand): the warning is about the header.
set(YELAN_ISA_FLAGS_avx2 -mavx2 -mfma -mf16c -Wno-psabi)
set(YELAN_ISA_FLAGS_avx512 -mavx512f -mavx512bw -mavx512vl -mavx512dq -mavx2 -mfma -mf16c -Wno-psabi
    -Wno-uninitialized -Wno-maybe-uninitialized)
set(YELAN_ISA_FLAGS_neon -Wno-psabi)

function(yelan_isa_variants target)
  cmake_parse_arguments(PARSE_ARGV 1 V "" "" "SOURCES;OPTIONS")
  foreach(isa_vl IN LISTS YELAN_VARIANT_ISAS)
    string(REPLACE ":" ";" isa_vl ${isa_vl})
    list(GET isa_vl 0 isa)
    list(GET isa_vl 1 vl)
    set(objects ${target}_${isa})
    add_library(${objects} OBJECT ${V_SOURCES})
    target_compile_definitions(${objects} PRIVATE YELAN_VARIANT_ISA=${isa} SIMD_VL=${vl})
    target_compile_options(${objects} PRIVATE ${YELAN_ISA_FLAGS_${isa}} ${V_OPTIONS})
    target_include_directories(${objects} PRIVATE ${PROJECT_SOURCE_DIR})
    target_link_libraries(${objects} PRIVATE OpenMP::OpenMP_CXX)
    target_sources(${target} PRIVATE $<TARGET_OBJECTS:${objects}>)
  endforeach()
endfunction()
