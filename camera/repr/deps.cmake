# camera/repr: libpng for `yelan repr --png`, and the TORE read-out kernels' ISA variants
# (the rest of yelan_camera stays baseline so the binary runs anywhere).
find_package(PNG REQUIRED)
target_link_libraries(yelan_camera PUBLIC PNG::PNG)
yelan_isa_variants(yelan_camera SOURCES ${CMAKE_CURRENT_SOURCE_DIR}/repr/tore_kernels_simd.cpp)
