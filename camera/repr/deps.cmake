# camera/repr: libpng for `yelan repr --png`, and per-file ISA flags for the TORE read-out
# kernel variants (the rest of yelan_camera stays baseline so the binary runs anywhere).
find_package(PNG REQUIRED)
target_link_libraries(yelan_camera PUBLIC PNG::PNG)
if(YELAN_ARCH STREQUAL "x86_64")
  set_source_files_properties(${CMAKE_CURRENT_SOURCE_DIR}/repr/tore_kernels_avx2.cpp
    PROPERTIES COMPILE_OPTIONS "-mavx2;-mfma;-mf16c")
  set_source_files_properties(${CMAKE_CURRENT_SOURCE_DIR}/repr/tore_kernels_avx512.cpp
    PROPERTIES COMPILE_OPTIONS "-mavx512f;-mavx512bw;-mavx512vl;-mavx512dq;-mavx2;-mfma;-mf16c;-Wno-uninitialized;-Wno-maybe-uninitialized")
endif()
