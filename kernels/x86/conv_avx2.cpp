// Direct convolution, AVX2+FMA: a 16-lane vector is 2 ymm, so 6 x 1 tiles use 12 of 16 ymm as accumulators.
#include <omp.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <utility>

#include "kernels/conv.h"

#define CONV_VL 8
#define CONV_R 6
#define CONV_NB 1
#define CONV_DW_CT 4

namespace yelan::kernels {
namespace {
#include "kernels/conv_direct.inl"
#include "kernels/conv_winograd.inl"
}  // namespace

extern const ConvKernels conv_avx2{Isa::avx2, conv_fwd, conv_bwd_data, conv_bwd_weights, conv_fwd_winograd};

}  // namespace yelan::kernels
