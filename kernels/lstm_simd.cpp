// ConvLSTM point-wise update on native vectors; the 4 gates of an element sit hb blocks
// apart, so each step reads 4 streams and writes 3, all unit-stride.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

#include "kernels/lstm.h"
#include "kernels/parallel.h"
#include "kernels/simd.h"

namespace yelan::kernels::YELAN_VARIANT_ISA {
namespace {

// body(n, begin, end) over every image and every 1024-float chunk of its E elements, in
// parallel: a live window is one image, so the chunks carry the parallelism.
template <class Body>
void for_each_chunk(const LstmShape& s, std::size_t E, Body&& body) {
  const std::ptrdiff_t chunks = std::ptrdiff_t((E + 1023) / 1024);
  on_team(worth_sharing_floats(std::size_t(s.n) * E), [&] {
#pragma omp for collapse(2) schedule(static)
    for (int n = 0; n < s.n; ++n)
      for (std::ptrdiff_t ch = 0; ch < chunks; ++ch)
        body(n, std::size_t(ch) * 1024, std::min(E, std::size_t(ch + 1) * 1024));
  });
}

void simd_lstm_fwd(const LstmShape& s, const float* gates, const float* c_prev, float* act, float* c, float* h,
                   float* tanh_c) {
  const std::size_t E = std::size_t(s.hb) * s.pixels * 16;
  for_each_chunk(s, E, [&](int n, std::size_t begin, std::size_t end) {
    const float* gi = gates + std::size_t(n) * 4 * E;
    float* ai = act + std::size_t(n) * 4 * E;
    const std::size_t so = std::size_t(n) * E;
    for (std::size_t e = begin; e < end; e += VL) {
      const vf i = vsigmoid(loadf(gi + e)), f = vsigmoid(loadf(gi + E + e));
      const vf o = vsigmoid(loadf(gi + 2 * E + e)), g = vtanh(loadf(gi + 3 * E + e));
      const vf cp = c_prev ? loadf(c_prev + so + e) : vf{};
      const vf cn = f * cp + i * g, t = vtanh(cn);
      storef(ai + e, i);
      storef(ai + E + e, f);
      storef(ai + 2 * E + e, o);
      storef(ai + 3 * E + e, g);
      storef(c + so + e, cn);
      storef(tanh_c + so + e, t);
      storef(h + so + e, o * t);
    }
  });
}

void simd_lstm_bwd(const LstmShape& s, const float* act, const float* c_prev, const float* tanh_c, const float* dh,
                   const float* dc, float* dgates, float* dc_prev) {
  const std::size_t E = std::size_t(s.hb) * s.pixels * 16;
  const vf one = splat(1.f);
  for_each_chunk(s, E, [&](int n, std::size_t begin, std::size_t end) {
    const float* a = act + std::size_t(n) * 4 * E;
    float* d = dgates + std::size_t(n) * 4 * E;
    const std::size_t so = std::size_t(n) * E;
    for (std::size_t e = begin; e < end; e += VL) {
      const vf i = loadf(a + e), f = loadf(a + E + e), o = loadf(a + 2 * E + e), g = loadf(a + 3 * E + e);
      const vf t = loadf(tanh_c + so + e), cp = c_prev ? loadf(c_prev + so + e) : vf{};
      const vf gh = loadf(dh + so + e);
      const vf dct = (dc ? loadf(dc + so + e) : vf{}) + gh * o * (one - t * t);
      storef(d + e, dct * g * i * (one - i));
      storef(d + E + e, dct * cp * f * (one - f));
      storef(d + 2 * E + e, gh * t * o * (one - o));
      storef(d + 3 * E + e, dct * i * (one - g * g));
      if (dc_prev) storef(dc_prev + so + e, dct * f);
    }
  });
}

constexpr LstmKernels kTable{Isa::YELAN_VARIANT_ISA, simd_lstm_fwd, simd_lstm_bwd};

}  // namespace
}  // namespace yelan::kernels::YELAN_VARIANT_ISA

YELAN_EXPORT_KERNELS(LstmKernels, lstm)
