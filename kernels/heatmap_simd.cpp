// Softmax and DSNT on native vectors: each pixel's 16 lanes are 16 joint maps, so the
// reductions over pixels are vector reductions with no shuffles.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "kernels/heatmap.h"
#include "kernels/parallel.h"
#include "kernels/simd.h"

namespace yelan::kernels::YELAN_VARIANT_ISA {
namespace {

constexpr int NQ = 16 / VL;

void simd_softmax_fwd(int planes, std::size_t pixels, const float* x, float* y) {
  on_team(worth_sharing_floats(std::size_t(planes) * pixels * 16), [&] {
#pragma omp for schedule(static)
    for (int p = 0; p < planes; ++p)
      for (int q = 0; q < NQ; ++q) {
        const float* xp = x + std::size_t(p) * pixels * 16 + q * VL;
        float* yp = y + std::size_t(p) * pixels * 16 + q * VL;
        vf m = loadf(xp);
        for (std::size_t i = 1; i < pixels; ++i) m = vmax(m, loadf(xp + i * 16));
        vf sum{};
        for (std::size_t i = 0; i < pixels; ++i) {
          const vf e = vexp(loadf(xp + i * 16) - m);
          storef(yp + i * 16, e);
          sum += e;
        }
        const vf inv = splat(1.f) / sum;
        for (std::size_t i = 0; i < pixels; ++i) storef(yp + i * 16, loadf(yp + i * 16) * inv);
      }
  });
}

void simd_softmax_bwd(int planes, std::size_t pixels, const float* y, const float* dy, float* dx) {
  on_team([&] {
#pragma omp for schedule(static)
    for (int p = 0; p < planes; ++p)
      for (int q = 0; q < NQ; ++q) {
        const std::size_t base = std::size_t(p) * pixels * 16 + q * VL;
        vf dot{};
        for (std::size_t i = 0; i < pixels; ++i) dot += loadf(y + base + i * 16) * loadf(dy + base + i * 16);
        for (std::size_t i = 0; i < pixels; ++i)
          storef(dx + base + i * 16, loadf(y + base + i * 16) * (loadf(dy + base + i * 16) - dot));
      }
  });
}

void simd_dsnt_fwd(int planes, int h, int w, const float* y, float* out) {
  for (int p = 0; p < planes; ++p)
    for (int q = 0; q < NQ; ++q) {
      vf ex{}, ey{};
      for (int r = 0; r < h; ++r) {
        vf row{}, wx{};
        for (int c = 0; c < w; ++c) {
          const vf v = loadf(y + ((std::size_t(p) * h + r) * w + c) * 16 + q * VL);
          row += v;
          wx += v * splat(dsnt_coordinate(c, w));
        }
        ex += wx;
        ey += row * splat(dsnt_coordinate(r, h));
      }
      storef(out + (p * 2 + 0) * 16 + q * VL, ex);
      storef(out + (p * 2 + 1) * 16 + q * VL, ey);
    }
}

void simd_dsnt_bwd(int planes, int h, int w, const float* dout, float* dy) {
  for (int p = 0; p < planes; ++p)
    for (int q = 0; q < NQ; ++q) {
      const vf gx = loadf(dout + (p * 2 + 0) * 16 + q * VL), gy = loadf(dout + (p * 2 + 1) * 16 + q * VL);
      for (int r = 0; r < h; ++r)
        for (int c = 0; c < w; ++c)
          storef(dy + ((std::size_t(p) * h + r) * w + c) * 16 + q * VL,
                 gx * splat(dsnt_coordinate(c, w)) + gy * splat(dsnt_coordinate(r, h)));
    }
}

constexpr HeatmapKernels kTable{Isa::YELAN_VARIANT_ISA, simd_softmax_fwd, simd_softmax_bwd, simd_dsnt_fwd,
                                simd_dsnt_bwd};

}  // namespace
}  // namespace yelan::kernels::YELAN_VARIANT_ISA

YELAN_EXPORT_KERNELS(HeatmapKernels, heatmap)
