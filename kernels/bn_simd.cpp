// Batch normalisation on native vectors: one 16-channel pixel is 16/VL vectors, so the
// per-channel statistics are plain vector sums over pixels. Sums run in float over chunks
// of 256 pixels and the chunk sums add up in double, so accuracy does not fall with the
// image size.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "kernels/bn.h"
#include "kernels/parallel.h"
#include "kernels/simd.h"

namespace yelan::kernels::YELAN_VARIANT_ISA {
namespace {

constexpr int NQ = 16 / VL;
constexpr std::size_t kChunk = 256;

// Per-lane double accumulation, over the planes of channel block b, of the two values
// f(i, q, &a, &b) yields for each pixel vector (one pass over memory for both sums).
template <class F>
void lane_sums2(const BnShape& s, int b, F&& f, double* out_a, double* out_b) {
  for (int l = 0; l < 16; ++l) out_a[l] = out_b[l] = 0;
  for (int n = 0; n < s.n; ++n) {
    const std::size_t base = (std::size_t(n) * s.cb + b) * s.pixels * 16;
    for (std::size_t p0 = 0; p0 < s.pixels; p0 += kChunk) {
      const std::size_t p1 = std::min(s.pixels, p0 + kChunk);
      vf acc_a[NQ] = {}, acc_b[NQ] = {};
      for (std::size_t p = p0; p < p1; ++p)
        for (int q = 0; q < NQ; ++q) f(base + p * 16 + q * VL, q, acc_a[q], acc_b[q]);
      for (int q = 0; q < NQ; ++q)
        for (int l = 0; l < VL; ++l) {
          out_a[q * VL + l] += acc_a[q][l];
          out_b[q * VL + l] += acc_b[q][l];
        }
    }
  }
}

template <class F>
void lane_sums(const BnShape& s, int b, F&& f, double* out) {
  double unused[16];
  lane_sums2(s, b, [&](std::size_t i, int q, vf& a, vf&) { a += f(i, q); }, out, unused);
}

// One pass: sums of (x - k) and (x - k)^2 with k the first pixel of each lane, a shift that
// keeps the variance free of the cancellation a plain sum of squares would suffer.
void simd_stats(const BnShape& s, const float* x, float* mean, float* var) {
  const double m = double(s.n) * s.pixels;
  on_team([&] {
#pragma omp for schedule(static)
    for (int b = 0; b < s.cb; ++b) {
      float k[16];
      for (int l = 0; l < 16; ++l) k[l] = x[std::size_t(b) * s.pixels * 16 + l];
      double s1[16], s2[16];
      lane_sums2(s, b, [&](std::size_t i, int q, vf& a, vf& sq) {
        const vf d = loadf(x + i) - loadf(k + q * VL);
        a += d;
        sq += d * d;
      }, s1, s2);
      for (int l = 0; l < 16; ++l) {
        const double d = s1[l] / m;
        mean[b * 16 + l] = float(k[l] + d);
        var[b * 16 + l] = float(std::max(0.0, s2[l] / m - d * d));
      }
    }
  });
}

// Per-channel y = (x - mean) * a + beta, a = gamma / sqrt(var + eps). Subtracting the mean
// first (rather than folding it into the shift) keeps tiny variances accurate.
void affine(const float* var, const float* gamma, float eps, int b, float* a) {
  for (int l = 0; l < 16; ++l) a[l] = gamma[b * 16 + l] / std::sqrt(var[b * 16 + l] + eps);
}

void simd_fwd(const BnShape& s, const float* x, const float* mean, const float* var, const float* gamma,
              const float* beta, float eps, bool relu, float* y) {
  on_team(worth_sharing_floats(std::size_t(s.n) * s.cb * s.pixels * 16), [&] {
#pragma omp for collapse(2) schedule(static)
    for (int n = 0; n < s.n; ++n)
      for (int b = 0; b < s.cb; ++b) {
        float a[16];
        affine(var, gamma, eps, b, a);
        vf va[NQ], vm[NQ], vb[NQ];
        for (int q = 0; q < NQ; ++q) {
          va[q] = loadf(a + q * VL);
          vm[q] = loadf(mean + b * 16 + q * VL);
          vb[q] = loadf(beta + b * 16 + q * VL);
        }
        const std::size_t base = (std::size_t(n) * s.cb + b) * s.pixels * 16;
        const vf zero{};
        for (std::size_t p = 0; p < s.pixels; ++p)
          for (int q = 0; q < NQ; ++q) {
            const std::size_t i = base + p * 16 + q * VL;
            vf v = (loadf(x + i) - vm[q]) * va[q] + vb[q];
            if (relu) v = vmax(v, zero);
            storef(y + i, v);
          }
      }
  });
}

void simd_bwd(const BnShape& s, const float* x, const float* y, const float* dy, const float* mean,
              const float* var, const float* gamma, float eps, bool relu, float* dx, float* dgamma,
              float* dbeta) {
  const double m = double(s.n) * s.pixels;
  on_team([&] {
#pragma omp for schedule(static)
    for (int b = 0; b < s.cb; ++b) {
      float inv[16], mu[16];
      for (int l = 0; l < 16; ++l) {
        inv[l] = 1.f / std::sqrt(var[b * 16 + l] + eps);
        mu[l] = mean[b * 16 + l];
      }
      auto grad = [&](std::size_t i) {
        const vf g = loadf(dy + i);
        return relu ? select(loadf(y + i) > vf{}, g, vf{}) : g;
      };
      double db[16], dg[16];
      lane_sums2(s, b, [&](std::size_t i, int q, vf& sb, vf& sg) {
        const vf g = grad(i);
        sb += g;
        sg += g * ((loadf(x + i) - loadf(mu + q * VL)) * loadf(inv + q * VL));
      }, db, dg);
      // dx = gamma * inv * (g - db/m - xhat * dg/m)
      float k1[16], k2[16], k3[16];
      for (int l = 0; l < 16; ++l) {
        const int ch = b * 16 + l;
        k1[l] = gamma[ch] * inv[l];
        k2[l] = float(db[l] / m);
        k3[l] = float(dg[l] / m);
        dgamma[ch] = float(dg[l]);
        dbeta[ch] = float(db[l]);
      }
      for (int n = 0; n < s.n; ++n) {
        const std::size_t base = (std::size_t(n) * s.cb + b) * s.pixels * 16;
        for (std::size_t p = 0; p < s.pixels; ++p)
          for (int q = 0; q < NQ; ++q) {
            const std::size_t i = base + p * 16 + q * VL;
            const vf xhat = (loadf(x + i) - loadf(mu + q * VL)) * loadf(inv + q * VL);
            storef(dx + i, loadf(k1 + q * VL) * (grad(i) - loadf(k2 + q * VL) - xhat * loadf(k3 + q * VL)));
          }
      }
    }
  });
}

constexpr BnKernels kTable{Isa::YELAN_VARIANT_ISA, simd_stats, simd_fwd, simd_bwd};

}  // namespace
}  // namespace yelan::kernels::YELAN_VARIANT_ISA

YELAN_EXPORT_KERNELS(BnKernels, bn)
