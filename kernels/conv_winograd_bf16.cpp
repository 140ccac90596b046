// Winograd F(4x4, 3x3) with its 36 GEMMs in bf16 pairs on AVX512-BF16, and the U-Net's 2x2
// up-sampling as four such GEMMs (conv_bf16.h says why and the contracts). Compiled with AVX-512 and AVX512-BF16 flags as an ISA variant of its
// own (avx512bf16, 16 floats a vector) and called only where winograd_bf16_available() holds.
// The transforms and the chunk loop are conv_winograd.inl's, shared with the fp32 kernel.
#include <immintrin.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <type_traits>
#include <utility>

#include "kernels/conv_bf16.h"
#include "kernels/parallel.h"
#include "kernels/simd.h"

namespace yelan::kernels::YELAN_VARIANT_ISA {
namespace {

#include "kernels/conv_winograd.inl"

static_assert(VL == 16, "the bf16 pairs fill one zmm: 16 output channels x 2 inputs");

// V is written as bf16 halves and read as 32-bit pairs: a type that may alias them.
typedef std::uint32_t bf16_pair __attribute__((may_alias));

struct GemmArgs {
  const bf16_pair* src;          // V: one 32-bit word per pair of input channels
  std::ptrdiff_t src_r, src_cb;  // words to the next tile / next input block
  const std::uint16_t* w;        // U: 8 rows of [16 outputs][2 inputs] per (output, input) block
  std::ptrdiff_t w_cb, w_ob;     // halves to the next input block / next output block
  int ncb, last_pairs;           // pairs of the last input block that hold channels
  float* dst;
  std::ptrdiff_t dst_r, dst_ob;
};

// R tiles x NB output blocks, the last of them half (8 channels, on ymm) when HALF: each pair
// of input channels is one broadcast word, dotted with NB weight rows by VDPBF16PS (two
// multiply-adds a lane, summed in fp32). R x NB accumulators: 24 chains for the widest tile.
template <int R, int NB, bool HALF>
void gemm_tile(const GemmArgs& a) {
  constexpr int NF = HALF ? NB - 1 : NB;
  __m512 acc[R][NF > 0 ? NF : 1];
  __m256 hacc[R];
#pragma GCC unroll 16
  for (int r = 0; r < R; ++r) {
#pragma GCC unroll 4
    for (int q = 0; q < NF; ++q) acc[r][q] = _mm512_setzero_ps();
    hacc[r] = _mm256_setzero_ps();
  }
  for (int cb = 0; cb < a.ncb; ++cb) {
    const int pairs = cb == a.ncb - 1 ? a.last_pairs : kBlock / 2;
    const bf16_pair* s = a.src + cb * a.src_cb;
    const std::uint16_t* w = a.w + cb * a.w_cb;
#pragma GCC unroll 8
    for (int k = 0; k < pairs; ++k) {
      __m512bh wv[NF > 0 ? NF : 1];
#pragma GCC unroll 4
      for (int q = 0; q < NF; ++q) wv[q] = (__m512bh)_mm512_loadu_si512(w + q * a.w_ob + k * 32);
      __m256bh hv{};
      if (HALF) hv = (__m256bh)_mm256_loadu_si256(reinterpret_cast<const __m256i*>(w + NF * a.w_ob + k * 32));
#pragma GCC unroll 16
      for (int r = 0; r < R; ++r) {
        const __m512i xv = _mm512_set1_epi32(int(s[r * a.src_r + k]));
#pragma GCC unroll 4
        for (int q = 0; q < NF; ++q) acc[r][q] = _mm512_dpbf16_ps(acc[r][q], (__m512bh)xv, wv[q]);
        if (HALF) hacc[r] = _mm256_dpbf16_ps(hacc[r], (__m256bh)_mm512_castsi512_si256(xv), hv);
      }
    }
  }
#pragma GCC unroll 16
  for (int r = 0; r < R; ++r) {
#pragma GCC unroll 4
    for (int q = 0; q < NF; ++q) _mm512_storeu_ps(a.dst + r * a.dst_r + q * a.dst_ob, acc[r][q]);
    if (HALF) {
      float* d = a.dst + r * a.dst_r + NF * a.dst_ob;
      _mm256_storeu_ps(d, hacc[r]);
      _mm256_storeu_ps(d + kBlock / 2, _mm256_setzero_ps());
    }
  }
}

constexpr int kTileR = 6, kTileNB = 4, kHalfTileR = 12;  // 24 zmm accumulators + 4 weight rows
using GemmFn = void (*)(const GemmArgs&);

template <int NB, bool HALF, int... R>
constexpr auto gemm_row(std::integer_sequence<int, R...>) {
  return std::array<GemmFn, sizeof...(R)>{&gemm_tile<R + 1, NB, HALF>...};
}
template <bool HALF, int... NB>
constexpr auto gemm_table(std::integer_sequence<int, NB...>) {
  return std::array<std::array<GemmFn, kTileR>, sizeof...(NB)>{
      gemm_row<NB + 1, HALF>(std::make_integer_sequence<int, kTileR>{})...};
}
constexpr auto kGemm = gemm_table<false>(std::make_integer_sequence<int, kTileNB>{});
constexpr auto kGemmHalfLast = gemm_table<true>(std::make_integer_sequence<int, kTileNB>{});
constexpr auto kGemmHalf = gemm_row<1, true>(std::make_integer_sequence<int, kHalfTileR>{});

// A last output block of 8 channels or fewer runs on ymm.
inline bool half_last_block(int oc) { return oc - ((oc + kBlock - 1) / kBlock - 1) * kBlock <= kBlock / 2; }

// What every GEMM of one convolution shares: V as [ICB][chunk][16] halves, U as [OCB][ICB]
// blocks of 16 x 16, M's strides to the next tile and the next output block.
GemmArgs channel_gemm(int ic, int chunk, std::ptrdiff_t dst_r, std::ptrdiff_t dst_ob) {
  const int icb = (ic + kBlock - 1) / kBlock;
  GemmArgs a;
  a.src_r = kBlock / 2;
  a.src_cb = std::ptrdiff_t(chunk) * kBlock / 2;
  a.w_cb = kBlock * kBlock;
  a.w_ob = std::ptrdiff_t(icb) * kBlock * kBlock;
  a.ncb = icb;
  a.last_pairs = (ic - (icb - 1) * kBlock + 1) / 2;  // an odd channel pairs with a zero lane
  a.dst_r = dst_r;
  a.dst_ob = dst_ob;
  return a;
}

// Rows of output blocks for one product: tiles of kTileR pixels x up to kTileNB blocks, the
// last block half where HALF_LAST (as conv_fwd_winograd_bf16's 36 products do).
void gemm_blocks(GemmArgs a, const std::uint16_t* w, int ocb, int icb, bool half_last, int tc, const bf16_pair* src,
                 float* dst) {
  for (int ob0 = 0; ob0 < ocb; ob0 += kTileNB) {
    const int nb = std::min(kTileNB, ocb - ob0);
    const bool half = ob0 + nb == ocb && half_last;
    const int tile_r = half && nb == 1 ? kHalfTileR : kTileR;
    const GemmFn* tiles = !half ? kGemm[nb - 1].data() : nb == 1 ? kGemmHalf.data() : kGemmHalfLast[nb - 1].data();
    a.w = w + std::ptrdiff_t(ob0) * icb * kBlock * kBlock;
    for (int t = 0; t < tc; t += tile_r) {
      a.src = src + t * a.src_r;
      a.dst = dst + ob0 * a.dst_ob + t * a.dst_r;
      tiles[std::min(tile_r, tc - t) - 1](a);
    }
  }
}

template <class Input>
void winograd_bf16(const ConvShape& s, const Input& in, const std::uint16_t* u, const float* bias, float* y) {
  const int ICB = s.icb(), OCB = s.ocb();
  const bool half_last = half_last_block(s.oc);
  const GemmArgs args = channel_gemm(s.ic, kWinoChunk, kWinoMTile, kWinoMBlock);
  const auto gemm = [&](const std::uint16_t* V, float* M, int tc) {
    const auto* words = reinterpret_cast<const bf16_pair*>(V);
    for (int xi = 0; xi < 36; ++xi)
      gemm_blocks(args, u + std::ptrdiff_t(xi) * OCB * ICB * kBlock * kBlock, OCB, ICB, half_last, tc,
                  words + wino_v_index(xi, 0, 0, ICB) / 2, M + wino_m_index(xi, 0, 0));
  };
  // VCVTNEPS2BF16 rounds to nearest even and flushes subnormals to zero, as to_bf16 does.
  const auto store_v = [](std::uint16_t* at, vf v) {
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(at), (__m256i)_mm512_cvtneps_pbh((__m512)v));
  };
  winograd_fwd<std::uint16_t>(s, in, bias, y, store_v, gemm);
}

void conv_fwd_winograd_bf16(const ConvShape& s, const float* x, const std::uint16_t* u, const float* bias, float* y) {
  winograd_bf16(s, PlainInput{x, s.icb(), s.ih, s.iw}, u, bias, y);
}

void conv_fwd_winograd_bf16_cat(const ConvShape& s, const ConcatInput& in, const std::uint16_t* u, const float* bias,
                                float* y) {
  winograd_bf16(s, CatInput{in, s.ih, s.iw}, u, bias, y);
}

// The U-Net's 2x2 stride-2 up-sampling: per output phase (dy, dx) a 1x1 convolution of the
// input, so four GEMMs over a chunk of input pixels (rounded to bf16 once, read by all four),
// each result stored with its bias at (2h + dy, 2w + dx). Weights [4][OCB][ICB][8 pairs][16][2].
constexpr int kUpChunk = 96;  // input pixels: 16 tiles of 6; V and M of the widest up in L2

void deconv2x2_fwd_bf16_pairs(const DeconvShape& d, const float* x, const std::uint16_t* w, const float* bias,
                              float* y) {
  const int ICB = d.icb(), OCB = d.ocb(), W = d.iw, OW = d.ow(), P = d.ih * d.iw;
  const bool half_last = half_last_block(d.oc);
  const GemmArgs a = channel_gemm(d.ic, kUpChunk, kBlock, std::ptrdiff_t(kUpChunk) * kBlock);
  const int chunks = (P + kUpChunk - 1) / kUpChunk;
  const std::ptrdiff_t x_plane = std::ptrdiff_t(P) * kBlock, y_plane = std::ptrdiff_t(d.oh()) * OW * kBlock;
  const std::size_t cs = std::size_t(kUpChunk) * kBlock;
  on_team(worth_sharing(d.as_conv().flops()), [&] {
    float* scratch = thread_scratch(std::size_t(ICB) * cs / 2 + std::size_t(4) * OCB * cs);
    std::uint16_t* V = reinterpret_cast<std::uint16_t*>(scratch);  // [ICB][chunk][16] halves
    float* M = scratch + std::size_t(ICB) * cs / 2;                 // [4][OCB][chunk][16]
#pragma omp for collapse(2) schedule(static)
    for (int n = 0; n < d.n; ++n)
      for (int ch = 0; ch < chunks; ++ch) {
        const int p0 = ch * kUpChunk, tc = std::min(kUpChunk, P - p0);
        for (int cb = 0; cb < ICB; ++cb) {  // a chunk of a plane is contiguous
          const float* xs = x + (std::ptrdiff_t(n) * ICB + cb) * x_plane + std::ptrdiff_t(p0) * kBlock;
          std::uint16_t* v = V + std::ptrdiff_t(cb) * cs;
          for (int t = 0; t < tc; ++t)
            _mm256_storeu_si256(reinterpret_cast<__m256i*>(v + t * kBlock),
                                (__m256i)_mm512_cvtneps_pbh(_mm512_loadu_ps(xs + t * kBlock)));
        }
        const auto* words = reinterpret_cast<const bf16_pair*>(V);
        for (int phase = 0; phase < 4; ++phase)
          gemm_blocks(a, w + std::ptrdiff_t(phase) * OCB * ICB * kBlock * kBlock, OCB, ICB, half_last, tc, words,
                      M + std::ptrdiff_t(phase) * OCB * cs);
        for (int ob = 0; ob < OCB; ++ob) {
          const __m512 b = bias ? _mm512_loadu_ps(bias + ob * kBlock) : _mm512_setzero_ps();
          float* yb = y + (std::ptrdiff_t(n) * OCB + ob) * y_plane;
          for (int t = 0, h = p0 / W, x0 = p0 % W; t < tc; ++t) {  // input pixel p0 + t is (h, x0)
            for (int phase = 0; phase < 4; ++phase) {
              const float* m = M + (std::ptrdiff_t(phase) * OCB + ob) * cs + t * kBlock;
              float* at = yb + (std::ptrdiff_t(2 * h + phase / 2) * OW + 2 * x0 + phase % 2) * kBlock;
              _mm512_storeu_ps(at, _mm512_add_ps(_mm512_loadu_ps(m), b));
            }
            if (++x0 == W) {
              x0 = 0;
              ++h;
            }
          }
        }
      }
  });
}

}  // namespace
}  // namespace yelan::kernels::YELAN_VARIANT_ISA

namespace yelan::kernels {
extern const WinogradBf16Kernels winograd_bf16_kernels{YELAN_VARIANT_ISA::conv_fwd_winograd_bf16,
                                                       YELAN_VARIANT_ISA::conv_fwd_winograd_bf16_cat,
                                                       YELAN_VARIANT_ISA::deconv2x2_fwd_bf16_pairs};
}
