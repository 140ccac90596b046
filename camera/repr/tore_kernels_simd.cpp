// The TORE read-out kernels compiled once per ISA (kernels/isa_variants.cmake): the plain
// loops of tore_kernels_impl.h, vectorised by GCC for that ISA; reached only through
// tore_kernels() after the CPU check.
#include "camera/repr/tore_kernels_impl.h"
#include "kernels/variant.h"

namespace yelan::camera {
extern const ToreKernels YELAN_VARIANT(tore) = {kernels::Isa::YELAN_VARIANT_ISA, tore_yelan_impl,
                                                        tore_baldwin_impl};
}  // namespace yelan::camera
