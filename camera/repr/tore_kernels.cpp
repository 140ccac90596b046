#include "camera/repr/tore_kernels.h"

#include "camera/repr/tore_kernels_impl.h"
#include "kernels/dispatch.h"

namespace yelan::camera {

const ToreKernels tore_scalar{kernels::Isa::scalar, tore_yelan_impl, tore_baldwin_impl};

YELAN_KERNEL_DISPATCH(ToreKernels, tore)

}  // namespace yelan::camera
