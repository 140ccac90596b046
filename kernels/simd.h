// The one vector vocabulary of every kernel variant: native-width vectors (GCC vector
// extensions, SIMD_VL floats: 16 AVX-512, 8 AVX2, 4 NEON) and the vector math on them.
// A family's vector code is written once over these and compiled per ISA (see variant.h);
// -ffp-contract=fast makes `a * b + c` one FMA.
#pragma once
#include "kernels/variant.h"

namespace yelan::kernels::YELAN_VARIANT_ISA {
namespace {

constexpr int VL = SIMD_VL;
typedef float vf __attribute__((vector_size(SIMD_VL * 4)));
typedef int vi __attribute__((vector_size(SIMD_VL * 4)));
// Memory goes through under-aligned aliases: buffers need only element alignment.
typedef float vfu __attribute__((vector_size(SIMD_VL * 4), aligned(4)));

inline vf loadf(const float* p) { return *reinterpret_cast<const vfu*>(p); }
inline void storef(float* p, vf v) { *reinterpret_cast<vfu*>(p) = v; }
inline vf splat(float s) { return vf{} + s; }
inline vf select(vi mask, vf a, vf b) { return (vf)((mask & (vi)a) | (~mask & (vi)b)); }
inline vf vmax(vf a, vf b) { return select(a > b, a, b); }
inline vf vmin(vf a, vf b) { return select(a < b, a, b); }
inline float hsum(vf v) {
  float s = 0;
  for (int i = 0; i < VL; ++i) s += v[i];
  return s;
}

// exp, log, sigmoid and tanh on native vectors. Accuracy, measured
// against double precision over dense sweeps by tests/kernels/test_vmath.cpp:
//   vexp  relative error <= 2.5e-7 on [-87, 88]          (degree-6 Taylor after 2^n reduction)
//   vlog  relative error <= 2e-7 on normal positive x  (2 atanh(f/(2+f)) series to s^9)
//   vsigmoid, vtanh absolute error <= 3e-7 everywhere   (from vexp)
// NaN in gives NaN out; exp overflows to +inf above 88.7 and flushes to 0 below -87.3.

inline vf vexp(vf x_in) {
  vf x = x_in;
  const vf hi = splat(88.3762626647949f), lo = splat(-87.3365447504f);
  const vi too_big = x > hi, too_small = x < lo, is_nan = x != x;
  x = vmin(vmax(x, lo), hi);
  // n = round(x / ln2); r = x - n ln2 with ln2 split so n*ln2_hi is exact.
  const vf t = x * splat(1.44269504088896341f) + splat(0.5f);
  vi n = __builtin_convertvector(t, vi);
  n += (vi)(__builtin_convertvector(n, vf) > t);  // truncation -> floor
  const vf nf = __builtin_convertvector(n, vf);
  vf r = x - nf * splat(0.693359375f);
  r = r - nf * splat(-2.12194440e-4f);
  vf p = splat(1.f / 720);
  p = p * r + splat(1.f / 120);
  p = p * r + splat(1.f / 24);
  p = p * r + splat(1.f / 6);
  p = p * r + splat(0.5f);
  p = p * r + splat(1.f);
  p = p * r + splat(1.f);
  // Scale by 2^n in two halves so n = 128 (x near 88.7) does not overflow the exponent.
  const vi n1 = n >> 1, n2 = n - n1;
  p = p * (vf)((n1 + 127) << 23) * (vf)((n2 + 127) << 23);
  p = select(too_big, splat(__builtin_inff()), p);
  p = select(too_small, vf{}, p);
  return select(is_nan, x_in, p);
}

inline vf vlog(vf x) {
  const vi is_nan = x != x, neg = x < vf{}, zero = x == vf{}, inf = x == splat(__builtin_inff());
  // Subnormals: scale into the normal range first.
  const vi sub = x < splat(1.17549435e-38f);
  x = select(sub, x * splat(8388608.f), x);
  vi bits = (vi)x;
  vi e = ((bits >> 23) & 0xff) - 127;
  e -= sub & 23;
  vf m = (vf)((bits & 0x007fffff) | 0x3f800000);  // [1, 2)
  const vi big = m > splat(1.41421356f);
  m = select(big, m * splat(0.5f), m);
  e += big & 1;
  const vf f = m - splat(1.f);
  const vf s = f / (splat(2.f) + f);
  const vf z = s * s;
  vf p = splat(1.f / 9);
  p = p * z + splat(1.f / 7);
  p = p * z + splat(1.f / 5);
  p = p * z + splat(1.f / 3);
  p = p * z + splat(1.f);
  const vf ef = __builtin_convertvector(e, vf);
  vf r = ef * splat(0.693147180559945f) + splat(2.f) * s * p;
  r = select(zero, splat(-__builtin_inff()), r);
  r = select(inf, splat(__builtin_inff()), r);
  r = select(neg | is_nan, splat(__builtin_nanf("")), r);
  return r;
}

inline vf vsigmoid(vf x) { return splat(1.f) / (splat(1.f) + vexp(-x)); }

inline vf vtanh(vf x) {
  const vf ax = vmax(x, -x);
  const vf e = vexp(vmin(ax, splat(9.f)) * splat(2.f));
  const vf t = splat(1.f) - splat(2.f) / (e + splat(1.f));
  const vf r = select(ax >= splat(9.f), splat(1.f), t);
  return select(x != x, x, select(x < vf{}, -r, r));
}

}  // namespace
}  // namespace yelan::kernels::YELAN_VARIANT_ISA
