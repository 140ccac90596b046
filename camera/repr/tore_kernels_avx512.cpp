// The TORE read-out kernels compiled for avx512 (flags from camera/repr/deps.cmake); only
// reached through tore_kernels() after the CPU check.
#if defined(__x86_64__)
#include "camera/repr/tore_kernels_impl.h"

namespace yelan::camera {
extern const ToreKernels tore_kernels_avx512;
const ToreKernels tore_kernels_avx512{kernels::Isa::avx512, tore_yelan_impl, tore_baldwin_impl};
}  // namespace yelan::camera
#endif
