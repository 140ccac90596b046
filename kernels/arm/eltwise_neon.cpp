// NEON variant of kernels/eltwise.h (ASIMD is baseline on aarch64: no extra flags).
#include <arm_neon.h>

#include "kernels/eltwise.h"

namespace yelan::kernels {
namespace {

void add(const float* a, const float* b, float* y, std::size_t n) {
  std::size_t i = 0;
  for (; i + 4 <= n; i += 4) vst1q_f32(y + i, vaddq_f32(vld1q_f32(a + i), vld1q_f32(b + i)));
  for (; i < n; ++i) y[i] = a[i] + b[i];
}
void axpy(float alpha, const float* x, float* y, std::size_t n) {
  std::size_t i = 0;
  for (; i + 4 <= n; i += 4) vst1q_f32(y + i, vfmaq_n_f32(vld1q_f32(y + i), vld1q_f32(x + i), alpha));
  for (; i < n; ++i) y[i] += alpha * x[i];
}
void relu(const float* x, float* y, std::size_t n) {
  const float32x4_t z = vdupq_n_f32(0.f);
  std::size_t i = 0;
  for (; i + 4 <= n; i += 4) vst1q_f32(y + i, vmaxq_f32(vld1q_f32(x + i), z));
  for (; i < n; ++i) y[i] = x[i] > 0.f ? x[i] : 0.f;
}
void relu_backward(const float* x, const float* dy, float* dx, std::size_t n) {
  const float32x4_t z = vdupq_n_f32(0.f);
  std::size_t i = 0;
  for (; i + 4 <= n; i += 4) {
    const uint32x4_t pos = vcgtq_f32(vld1q_f32(x + i), z);
    vst1q_f32(dx + i, vreinterpretq_f32_u32(vandq_u32(pos, vreinterpretq_u32_f32(vld1q_f32(dy + i)))));
  }
  for (; i < n; ++i) dx[i] = x[i] > 0.f ? dy[i] : 0.f;
}
float dot(const float* a, const float* b, std::size_t n) {
  float32x4_t s0 = vdupq_n_f32(0.f), s1 = vdupq_n_f32(0.f);
  std::size_t i = 0;
  for (; i + 8 <= n; i += 8) {
    s0 = vfmaq_f32(s0, vld1q_f32(a + i), vld1q_f32(b + i));
    s1 = vfmaq_f32(s1, vld1q_f32(a + i + 4), vld1q_f32(b + i + 4));
  }
  for (; i + 4 <= n; i += 4) s0 = vfmaq_f32(s0, vld1q_f32(a + i), vld1q_f32(b + i));
  float s = vaddvq_f32(vaddq_f32(s0, s1));
  for (; i < n; ++i) s += a[i] * b[i];
  return s;
}

}  // namespace

extern const EltwiseKernels eltwise_neon{Isa::neon, add, axpy, relu, relu_backward, dot};

}  // namespace yelan::kernels
