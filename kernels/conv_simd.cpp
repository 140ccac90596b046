// Convolution on native vectors: the direct register-blocked kernels (forward,
// backward-data, backward-weights) and Winograd F(4,3) inference, compiled once per ISA.
// In a profile: yelan::kernels::<isa>::(anonymous)::tile<R, NB> is the R-pixel x NB-block tile.
#include <omp.h>

#include <algorithm>
#include <array>
#include <type_traits>
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

// The fp32 Winograd: its 36 GEMMs over channels are the direct convolution's tile with one tap.
template <class Input>
void winograd_fp32(const ConvShape& s, const Input& in, const float* u, const float* bias, float* y) {
  const int ICB = s.icb(), OCB = s.ocb();
  const std::ptrdiff_t cs = std::ptrdiff_t(kWinoChunk) * kBlock;
  const bool half_last = s.oc - (OCB - 1) * kBlock <= kBlock / 2;  // see tile
  const auto gemm = [&](const float* V, float* M, int tc) {
    const Tap one{0, 0};
    for (int xi = 0; xi < 36; ++xi)
      for (int ob0 = 0; ob0 < OCB; ob0 += CONV_NB) {
        const int nb = std::min(CONV_NB, OCB - ob0);
        int tile_r;
        const TileFn* tiles = tiles_for_group(nb, ob0 + nb == OCB && half_last, &tile_r);
        TileArgs a;
        a.src_r = kBlock;
        a.src_cb = cs;
        a.w = u + (std::ptrdiff_t(xi) * OCB + ob0) * ICB * kBlock * kBlock;
        a.w_cb = kBlock * kBlock;
        a.w_ob = std::ptrdiff_t(ICB) * kBlock * kBlock;
        a.taps = &one;
        a.ntaps = 1;
        a.ncb = ICB;
        a.last_lanes = s.ic - (ICB - 1) * kBlock;
        a.dst_r = kWinoMTile;
        a.dst_ob = kWinoMBlock;
        a.bias = nullptr;
        for (int t = 0; t < tc; t += tile_r) {
          a.src = V + wino_v_index(xi, 0, t, ICB);
          a.dst = M + wino_m_index(xi, ob0, t);
          tiles[std::min(tile_r, tc - t) - 1](a);
        }
      }
  };
  winograd_fwd<float>(s, in, bias, y, [](float* at, vf v) { storef(at, v); }, gemm);
}

void conv_fwd_winograd(const ConvShape& s, const float* x, const float* u, const float* bias, float* y) {
  winograd_fp32(s, PlainInput{x, s.icb(), s.ih, s.iw}, u, bias, y);
}

void conv_fwd_winograd_cat(const ConvShape& s, const ConcatInput& in, const float* u, const float* bias, float* y) {
  winograd_fp32(s, CatInput{in, s.ih, s.iw}, u, bias, y);
}

constexpr ConvKernels kTable{Isa::YELAN_VARIANT_ISA, conv_fwd,         conv_bwd_data, conv_bwd_weights,
                             conv_fwd_winograd,      conv_fwd_winograd_cat};

}  // namespace
}  // namespace yelan::kernels::YELAN_VARIANT_ISA

YELAN_EXPORT_KERNELS(ConvKernels, conv)
