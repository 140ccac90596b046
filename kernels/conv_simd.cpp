// Convolution on native vectors: the direct register-blocked kernels (forward,
// backward-data, backward-weights) and Winograd F(4,3) inference, compiled once per ISA.
// In a profile: yelan::kernels::<isa>::(anonymous)::tile<R, NB> is the R-pixel x NB-block tile.
#include <omp.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <utility>

#include "kernels/conv.h"
#include "kernels/parallel.h"
#include "kernels/simd.h"

namespace yelan::kernels::YELAN_VARIANT_ISA {
namespace {

// The tile fills the register file: AVX-512 6 px x 4 blocks = 24 zmm accumulators + 4 weight
// vectors of 32; AVX2 6 x 1 block (2 ymm each) = 12 of 16 ymm; NEON 6 x 1 (4 q each) = 24 of 32.
constexpr int CONV_R = 6;
constexpr int CONV_NB = VL == 16 ? 4 : 1;
constexpr int CONV_DW_CT = VL == 16 ? 16 : 4;

#include "kernels/conv_direct.inl"
#include "kernels/conv_winograd.inl"

constexpr ConvKernels kTable{Isa::YELAN_VARIANT_ISA, conv_fwd, conv_bwd_data, conv_bwd_weights, conv_fwd_winograd};

}  // namespace
}  // namespace yelan::kernels::YELAN_VARIANT_ISA

YELAN_EXPORT_KERNELS(ConvKernels, conv)
