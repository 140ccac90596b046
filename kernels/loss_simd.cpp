// Loss kernels on native vectors. Partial sums stay in float vectors for 1024 elements
// and then add up in double, so large masks do not lose the small per-pixel terms.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "kernels/loss.h"
#include "kernels/simd.h"

namespace yelan::kernels::YELAN_VARIANT_ISA {
namespace {

template <class Step>
double chunked_sum(std::size_t n, Step&& step) {
  double total = 0;
  std::size_t i = 0;
  while (i + VL <= n) {
    vf acc{};
    const std::size_t end = std::min(n - n % VL, i + 1024);
    for (; i < end; i += VL) acc += step(i);
    total += hsum(acc);
  }
  return total;
}

void tail_copy(const float* src, std::size_t i, std::size_t n, float* dst, float fill) {
  for (int k = 0; k < VL; ++k) dst[k] = i + k < n ? src[i + k] : fill;
}

vf bce_terms(vf v, vf t, vf* grad) {
  const vf e = vexp(-vmax(v, -v));
  *grad = vsigmoid(v) - t;
  return vmax(v, vf{}) - v * t + vlog(splat(1.f) + e);
}

double simd_bce_logits(const float* x, const float* t, std::size_t n, float* dx) {
  double sum = chunked_sum(n, [&](std::size_t i) {
    vf g;
    const vf l = bce_terms(loadf(x + i), loadf(t + i), &g);
    storef(dx + i, g);
    return l;
  });
  const std::size_t i = n - n % VL;
  if (i < n) {
    float xv[VL], tv[VL], gv[VL];
    tail_copy(x, i, n, xv, 0.f);
    tail_copy(t, i, n, tv, 0.f);
    vf g;
    const vf l = bce_terms(loadf(xv), loadf(tv), &g);
    storef(gv, g);
    for (std::size_t k = 0; i + k < n; ++k) {
      sum += l[k];
      dx[i + k] = gv[k];
    }
  }
  return sum;
}

vf jsd_terms(vf p, vf q, vf eps, vf* grad) {
  const vf a = vmax(p, eps), b = vmax(q, eps), m = splat(0.5f) * (a + b);
  const vf la = vlog(a / m), lb = vlog(b / m);
  *grad = splat(0.5f) * la;
  return splat(0.5f) * (p * la + q * lb);
}

double simd_jsd(const float* p, const float* q, std::size_t n, float eps, float* dp) {
  const vf ve = splat(eps);
  double sum = chunked_sum(n, [&](std::size_t i) {
    vf g;
    const vf l = jsd_terms(loadf(p + i), loadf(q + i), ve, &g);
    storef(dp + i, g);
    return l;
  });
  const std::size_t i = n - n % VL;
  if (i < n) {
    float pv[VL], qv[VL], gv[VL];
    tail_copy(p, i, n, pv, 1.f);  // padding lanes: p = q gives a zero term
    tail_copy(q, i, n, qv, 1.f);
    vf g;
    const vf l = jsd_terms(loadf(pv), loadf(qv), ve, &g);
    storef(gv, g);
    for (std::size_t k = 0; i + k < n; ++k) {
      sum += l[k];
      dp[i + k] = gv[k];
    }
  }
  return sum;
}

constexpr LossKernels kTable{Isa::YELAN_VARIANT_ISA, simd_bce_logits, simd_jsd};

}  // namespace
}  // namespace yelan::kernels::YELAN_VARIANT_ISA

YELAN_EXPORT_KERNELS(LossKernels, loss)
