#include "kernels/pool.h"

#include <cstring>
#include <limits>

#include "kernels/dispatch.h"

namespace yelan::kernels {
namespace {

constexpr int L = 16;

void max_fwd(const PoolShape& s, const float* x, float* y, std::int32_t* arg) {
  const int OH = s.oh(), OW = s.ow();
  for (int p = 0; p < s.planes; ++p)
    for (int oh = 0; oh < OH; ++oh)
      for (int ow = 0; ow < OW; ++ow)
        for (int l = 0; l < L; ++l) {
          float best = -std::numeric_limits<float>::infinity();
          std::int32_t at = -1;
          for (int kh = 0; kh < s.k; ++kh)
            for (int kw = 0; kw < s.k; ++kw) {
              const int ih = oh * s.stride - s.pad + kh, iw = ow * s.stride - s.pad + kw;
              if (ih < 0 || ih >= s.ih || iw < 0 || iw >= s.iw) continue;
              const float v = x[((std::size_t(p) * s.ih + ih) * s.iw + iw) * L + l];
              if (at < 0 || v > best) {  // first maximum wins, as in PyTorch
                best = v;
                at = ih * s.iw + iw;
              }
            }
          const std::size_t o = ((std::size_t(p) * OH + oh) * OW + ow) * L + l;
          y[o] = best;
          arg[o] = at;
        }
}

void max_bwd(const PoolShape& s, const float* dy, const std::int32_t* arg, float* dx) {
  const int OH = s.oh(), OW = s.ow();
  std::memset(dx, 0, std::size_t(s.planes) * s.ih * s.iw * L * sizeof(float));
  for (int p = 0; p < s.planes; ++p)
    for (std::size_t o = 0; o < std::size_t(OH) * OW * L; ++o) {
      const std::size_t oi = std::size_t(p) * OH * OW * L + o;
      dx[(std::size_t(p) * s.ih * s.iw + arg[oi]) * L + o % L] += dy[oi];
    }
}

void avg_fwd(int planes, std::size_t pixels, const float* x, float* y) {
  for (int p = 0; p < planes; ++p)
    for (int l = 0; l < L; ++l) {
      double s = 0;
      for (std::size_t i = 0; i < pixels; ++i) s += x[(p * pixels + i) * L + l];
      y[p * L + l] = float(s / double(pixels));
    }
}

void avg_bwd(int planes, std::size_t pixels, const float* dy, float* dx) {
  for (int p = 0; p < planes; ++p)
    for (std::size_t i = 0; i < pixels; ++i)
      for (int l = 0; l < L; ++l) dx[(p * pixels + i) * L + l] = dy[p * L + l] / float(pixels);
}

}  // namespace

const PoolKernels pool_scalar{Isa::scalar, max_fwd, max_bwd, avg_fwd, avg_bwd};
YELAN_KERNEL_DISPATCH(PoolKernels, pool)

}  // namespace yelan::kernels
