// Pooling on native vectors: the 16 lanes of a pixel are independent channels, so a max
// over the window is a vector max and the argmax a vector select of pixel indices.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "kernels/pool.h"
#include "kernels/parallel.h"
#include "kernels/simd.h"

namespace yelan::kernels::YELAN_VARIANT_ISA {
namespace {

constexpr int NQ = 16 / VL;

void simd_max_fwd(const PoolShape& s, const float* x, float* y, std::int32_t* arg) {
  const int OH = s.oh(), OW = s.ow();
  on_team(worth_sharing_floats(std::size_t(s.planes) * s.ih * s.iw * 16), [&] {
#pragma omp for collapse(2) schedule(static)
    for (int p = 0; p < s.planes; ++p)
      for (int oh = 0; oh < OH; ++oh) {
        const int h0 = std::max(0, oh * s.stride - s.pad), h1 = std::min(s.ih, oh * s.stride - s.pad + s.k);
        for (int ow = 0; ow < OW; ++ow) {
          const int w0 = std::max(0, ow * s.stride - s.pad), w1 = std::min(s.iw, ow * s.stride - s.pad + s.k);
          const std::size_t o = ((std::size_t(p) * OH + oh) * OW + ow) * 16;
          for (int q = 0; q < NQ; ++q) {
            vf best = loadf(x + ((std::size_t(p) * s.ih + h0) * s.iw + w0) * 16 + q * VL);
            vi at = vi{} + (h0 * s.iw + w0);
            for (int ih = h0; ih < h1; ++ih)
              for (int iw = w0; iw < w1; ++iw) {
                const vf v = loadf(x + ((std::size_t(p) * s.ih + ih) * s.iw + iw) * 16 + q * VL);
                const vi better = v > best;  // strict: the first maximum wins
                best = select(better, v, best);
                at = (better & (vi{} + (ih * s.iw + iw))) | (~better & at);
              }
            storef(y + o + q * VL, best);
            __builtin_memcpy(arg + o + q * VL, &at, sizeof at);  // one vector store
          }
        }
      }
  });
}

void simd_max_bwd(const PoolShape& s, const float* dy, const std::int32_t* arg, float* dx) {
  const int OH = s.oh(), OW = s.ow();
  const std::size_t in_plane = std::size_t(s.ih) * s.iw * 16, out_plane = std::size_t(OH) * OW * 16;
  on_team([&] {
#pragma omp for schedule(static)
    for (int p = 0; p < s.planes; ++p) {  // planes never share dx: no races
      float* d = dx + p * in_plane;
      std::fill(d, d + in_plane, 0.f);
      const float* g = dy + p * out_plane;
      const std::int32_t* a = arg + p * out_plane;
      for (std::size_t o = 0; o < out_plane; ++o) d[std::size_t(a[o]) * 16 + o % 16] += g[o];
    }
  });
}

void simd_avg_fwd(int planes, std::size_t pixels, const float* x, float* y) {
  on_team([&] {
#pragma omp for schedule(static)
    for (int p = 0; p < planes; ++p) {
      double sum[16] = {};
      for (std::size_t i0 = 0; i0 < pixels; i0 += 256) {
        vf acc[NQ] = {};
        for (std::size_t i = i0; i < std::min(pixels, i0 + 256); ++i)
          for (int q = 0; q < NQ; ++q) acc[q] += loadf(x + (p * pixels + i) * 16 + q * VL);
        for (int q = 0; q < NQ; ++q)
          for (int l = 0; l < VL; ++l) sum[q * VL + l] += acc[q][l];
      }
      for (int l = 0; l < 16; ++l) y[p * 16 + l] = float(sum[l] / double(pixels));
    }
  });
}

void simd_avg_bwd(int planes, std::size_t pixels, const float* dy, float* dx) {
  on_team([&] {
#pragma omp for schedule(static)
    for (int p = 0; p < planes; ++p)
      for (int q = 0; q < NQ; ++q) {
        // divide, not multiply by the reciprocal: bit-identical to the reference
        const vf g = loadf(dy + p * 16 + q * VL) / splat(float(pixels));
        for (std::size_t i = 0; i < pixels; ++i) storef(dx + (p * pixels + i) * 16 + q * VL, g);
      }
  });
}

constexpr PoolKernels kTable{Isa::YELAN_VARIANT_ISA, simd_max_fwd, simd_max_bwd, simd_avg_fwd, simd_avg_bwd};

}  // namespace
}  // namespace yelan::kernels::YELAN_VARIANT_ISA

YELAN_EXPORT_KERNELS(PoolKernels, pool)
