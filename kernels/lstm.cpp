#include "kernels/lstm.h"

#include <cmath>

#include "kernels/dispatch.h"

namespace yelan::kernels {
namespace {

// Element e of image n: gate k (0 i, 1 f, 2 o, 3 g) lives at gate_index(n, k, e).
struct Index {
  const LstmShape& s;
  std::size_t per_block() const { return s.pixels * 16; }
  std::size_t state(int n, std::size_t e) const { return std::size_t(n) * s.hb * per_block() + e; }
  std::size_t gate(int n, int k, std::size_t e) const {
    return (std::size_t(n) * 4 + k) * s.hb * per_block() + e;
  }
};

float sigmoid(float v) { return 1.f / (1.f + std::exp(-v)); }

void fwd(const LstmShape& s, const float* gates, const float* c_prev, float* act, float* c, float* h, float* tanh_c) {
  const Index ix{s};
  const std::size_t E = s.hb * ix.per_block();
  for (int n = 0; n < s.n; ++n)
    for (std::size_t e = 0; e < E; ++e) {
      const float i = sigmoid(gates[ix.gate(n, 0, e)]), f = sigmoid(gates[ix.gate(n, 1, e)]);
      const float o = sigmoid(gates[ix.gate(n, 2, e)]), g = std::tanh(gates[ix.gate(n, 3, e)]);
      const float cp = c_prev ? c_prev[ix.state(n, e)] : 0.f;
      const float cn = f * cp + i * g, t = std::tanh(cn);
      act[ix.gate(n, 0, e)] = i;
      act[ix.gate(n, 1, e)] = f;
      act[ix.gate(n, 2, e)] = o;
      act[ix.gate(n, 3, e)] = g;
      c[ix.state(n, e)] = cn;
      tanh_c[ix.state(n, e)] = t;
      h[ix.state(n, e)] = o * t;
    }
}

void bwd(const LstmShape& s, const float* act, const float* c_prev, const float* tanh_c, const float* dh,
         const float* dc, float* dgates, float* dc_prev) {
  const Index ix{s};
  const std::size_t E = s.hb * ix.per_block();
  for (int n = 0; n < s.n; ++n)
    for (std::size_t e = 0; e < E; ++e) {
      const float i = act[ix.gate(n, 0, e)], f = act[ix.gate(n, 1, e)];
      const float o = act[ix.gate(n, 2, e)], g = act[ix.gate(n, 3, e)];
      const std::size_t k = ix.state(n, e);
      const float t = tanh_c[k], cp = c_prev ? c_prev[k] : 0.f;
      const float dct = (dc ? dc[k] : 0.f) + dh[k] * o * (1.f - t * t);
      dgates[ix.gate(n, 0, e)] = dct * g * i * (1.f - i);
      dgates[ix.gate(n, 1, e)] = dct * cp * f * (1.f - f);
      dgates[ix.gate(n, 2, e)] = dh[k] * t * o * (1.f - o);
      dgates[ix.gate(n, 3, e)] = dct * i * (1.f - g * g);
      if (dc_prev) dc_prev[k] = dct * f;
    }
}

}  // namespace

const LstmKernels lstm_scalar{Isa::scalar, fwd, bwd};
YELAN_KERNEL_DISPATCH(LstmKernels, lstm)

}  // namespace yelan::kernels
