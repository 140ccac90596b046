// Direct convolution, AVX-512: 32 zmm hold 6 x 4 accumulators, 4 weight vectors; broadcasts fold into the FMA.
#include <omp.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <utility>

#include "kernels/conv.h"

#define CONV_VL 16
#define CONV_R 6
#define CONV_NB 4
#define CONV_DW_CT 16

namespace yelan::kernels {
namespace {
#include "kernels/conv_direct.inl"
#include "kernels/conv_winograd.inl"
}  // namespace

extern const ConvKernels conv_avx512{Isa::avx512, conv_fwd, conv_bwd_data, conv_bwd_weights, conv_fwd_winograd};

}  // namespace yelan::kernels
