#include "camera/repr/tore_kernels.h"

#include "camera/repr/tore_kernels_impl.h"
#include "kernels/dispatch.h"

namespace yelan::camera {

const ToreKernels tore_kernels_scalar{kernels::Isa::scalar, tore_yelan_impl, tore_baldwin_impl};

#if defined(__x86_64__)
extern const ToreKernels tore_kernels_avx2;
extern const ToreKernels tore_kernels_avx512;
#endif

const ToreKernels& tore_kernels(kernels::Isa isa) {
  kernels::Variants<ToreKernels> v;
  v.scalar = &tore_kernels_scalar;
#if defined(__x86_64__)
  v.avx2 = &tore_kernels_avx2;
  v.avx512 = &tore_kernels_avx512;
#endif
  return kernels::select_variant(v, isa);
}

}  // namespace yelan::camera
