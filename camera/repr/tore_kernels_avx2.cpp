// The TORE read-out kernels compiled for avx2 (flags from camera/repr/deps.cmake); only
// reached through tore_kernels() after the CPU check.
#if defined(__x86_64__)
#include "camera/repr/tore_kernels_impl.h"

namespace yelan::camera {
extern const ToreKernels tore_kernels_avx2;
const ToreKernels tore_kernels_avx2{kernels::Isa::avx2, tore_yelan_impl, tore_baldwin_impl};
}  // namespace yelan::camera
#endif
