// Element-wise kernels on native vectors; tails run the same formula one element at a time.
#include <cstddef>

#include "kernels/eltwise.h"
#include "kernels/simd.h"

namespace yelan::kernels::YELAN_VARIANT_ISA {
namespace {

void add(const float* a, const float* b, float* y, std::size_t n) {
  std::size_t i = 0;
  for (; i + VL <= n; i += VL) storef(y + i, loadf(a + i) + loadf(b + i));
  for (; i < n; ++i) y[i] = a[i] + b[i];
}
void axpy(float alpha, const float* x, float* y, std::size_t n) {
  const vf va = splat(alpha);
  std::size_t i = 0;
  for (; i + VL <= n; i += VL) storef(y + i, va * loadf(x + i) + loadf(y + i));
  for (; i < n; ++i) y[i] += alpha * x[i];
}
void relu(const float* x, float* y, std::size_t n) {
  std::size_t i = 0;
  for (; i + VL <= n; i += VL) {
    const vf v = loadf(x + i);
    storef(y + i, select(v > vf{}, v, vf{}));
  }
  for (; i < n; ++i) y[i] = x[i] > 0.f ? x[i] : 0.f;
}
void relu_backward(const float* x, const float* dy, float* dx, std::size_t n) {
  std::size_t i = 0;
  for (; i + VL <= n; i += VL) storef(dx + i, select(loadf(x + i) > vf{}, loadf(dy + i), vf{}));
  for (; i < n; ++i) dx[i] = x[i] > 0.f ? dy[i] : 0.f;
}
// Two accumulators: consecutive FMAs into one would wait on each other's latency.
float dot(const float* a, const float* b, std::size_t n) {
  vf s0{}, s1{};
  std::size_t i = 0;
  for (; i + 2 * VL <= n; i += 2 * VL) {
    s0 += loadf(a + i) * loadf(b + i);
    s1 += loadf(a + i + VL) * loadf(b + i + VL);
  }
  for (; i + VL <= n; i += VL) s0 += loadf(a + i) * loadf(b + i);
  float tail = 0;
  for (; i < n; ++i) tail += a[i] * b[i];
  return hsum(s0 + s1) + tail;
}

constexpr EltwiseKernels kTable{Isa::YELAN_VARIANT_ISA, add, axpy, relu, relu_backward, dot};

}  // namespace
}  // namespace yelan::kernels::YELAN_VARIANT_ISA

YELAN_EXPORT_KERNELS(EltwiseKernels, eltwise)
