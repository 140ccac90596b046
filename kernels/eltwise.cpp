#include "kernels/eltwise.h"

#include "kernels/dispatch.h"

namespace yelan::kernels {
namespace {

void add(const float* a, const float* b, float* y, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) y[i] = a[i] + b[i];
}
void axpy(float alpha, const float* x, float* y, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) y[i] += alpha * x[i];
}
void relu(const float* x, float* y, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) y[i] = x[i] > 0.f ? x[i] : 0.f;
}
void relu_backward(const float* x, const float* dy, float* dx, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) dx[i] = x[i] > 0.f ? dy[i] : 0.f;
}
float dot(const float* a, const float* b, std::size_t n) {
  double s = 0;
  for (std::size_t i = 0; i < n; ++i) s += double(a[i]) * b[i];
  return static_cast<float>(s);
}

}  // namespace

const EltwiseKernels eltwise_scalar{Isa::scalar, add, axpy, relu, relu_backward, dot};

#if defined(__x86_64__)
extern const EltwiseKernels eltwise_avx2;
extern const EltwiseKernels eltwise_avx512;
#elif defined(__aarch64__)
extern const EltwiseKernels eltwise_neon;
#endif

const EltwiseKernels& eltwise_kernels(Isa isa) {
  Variants<EltwiseKernels> v;
  v.scalar = &eltwise_scalar;
#if defined(__x86_64__)
  v.avx2 = &eltwise_avx2;
  v.avx512 = &eltwise_avx512;
#elif defined(__aarch64__)
  v.neon = &eltwise_neon;
#endif
  return select_variant(v, isa);
}

}  // namespace yelan::kernels
