// Double-precision NCHW/OIHW convolution for tests, and blocked-layout packing of plain
// arrays, written independently of kernels/ so the kernels have something to disagree with.
#pragma once
#include <cmath>
#include <cstddef>
#include <vector>

#include "kernels/conv.h"

namespace yelan::test {

using kernels::ConvShape;
using kernels::kBlock;

struct ConvRef {
  std::vector<double> y, y_abs;  // y and sum |x*w| per output (bias included)
  std::vector<double> dx, dw, db;
};

inline ConvRef conv_reference(const ConvShape& s, const std::vector<float>& x, const std::vector<float>& w,
                              const std::vector<float>& b, const std::vector<float>& dy) {
  const int OH = s.oh(), OW = s.ow();
  ConvRef r;
  r.y.assign(std::size_t(s.n) * s.oc * OH * OW, 0.0);
  r.y_abs = r.y;
  r.dx.assign(x.size(), 0.0);
  r.dw.assign(w.size(), 0.0);
  r.db.assign(s.oc, 0.0);
  for (int n = 0; n < s.n; ++n)
    for (int o = 0; o < s.oc; ++o)
      for (int oh = 0; oh < OH; ++oh)
        for (int ow = 0; ow < OW; ++ow) {
          const std::size_t yi = ((std::size_t(n) * s.oc + o) * OH + oh) * OW + ow;
          double acc = b.empty() ? 0.0 : b[o], mag = std::abs(acc);
          const double g = dy[yi];
          r.db[o] += g;
          for (int i = 0; i < s.ic; ++i)
            for (int kh = 0; kh < s.kh; ++kh) {
              const int ih = oh * s.stride - s.pad_h + kh;
              if (ih < 0 || ih >= s.ih) continue;
              for (int kw = 0; kw < s.kw; ++kw) {
                const int iw = ow * s.stride - s.pad_w + kw;
                if (iw < 0 || iw >= s.iw) continue;
                const std::size_t xi = ((std::size_t(n) * s.ic + i) * s.ih + ih) * s.iw + iw;
                const std::size_t wi = ((std::size_t(o) * s.ic + i) * s.kh + kh) * s.kw + kw;
                acc += double(x[xi]) * w[wi];
                mag += std::abs(double(x[xi]) * w[wi]);
                r.dx[xi] += g * w[wi];
                r.dw[wi] += g * x[xi];
              }
            }
          r.y[yi] = acc;
          r.y_abs[yi] = mag;
        }
  return r;
}

// Plain NCHW (C channels) -> [N][ceil(C/16)][H][W][16] with zero padding lanes, and back.
inline std::vector<float> to_blocked(const std::vector<float>& a, int N, int C, int H, int W) {
  const int CB = (C + kBlock - 1) / kBlock;
  std::vector<float> out(std::size_t(N) * CB * H * W * kBlock, 0.f);
  for (int n = 0; n < N; ++n)
    for (int c = 0; c < C; ++c)
      for (int h = 0; h < H; ++h)
        for (int w = 0; w < W; ++w)
          out[(((std::size_t(n) * CB + c / kBlock) * H + h) * W + w) * kBlock + c % kBlock] =
              a[((std::size_t(n) * C + c) * H + h) * W + w];
  return out;
}

inline std::vector<float> from_blocked(const std::vector<float>& a, int N, int C, int H, int W) {
  const int CB = (C + kBlock - 1) / kBlock;
  std::vector<float> out(std::size_t(N) * C * H * W);
  for (int n = 0; n < N; ++n)
    for (int c = 0; c < C; ++c)
      for (int h = 0; h < H; ++h)
        for (int w = 0; w < W; ++w)
          out[((std::size_t(n) * C + c) * H + h) * W + w] =
              a[(((std::size_t(n) * CB + c / kBlock) * H + h) * W + w) * kBlock + c % kBlock];
  return out;
}

// True if every padding lane (channel >= C) of a blocked array is exactly zero.
inline bool padding_is_zero(const std::vector<float>& a, int N, int C, int H, int W) {
  const int CB = (C + kBlock - 1) / kBlock;
  for (int n = 0; n < N; ++n)
    for (int c = C; c < CB * kBlock; ++c)
      for (int h = 0; h < H; ++h)
        for (int w = 0; w < W; ++w)
          if (a[(((std::size_t(n) * CB + c / kBlock) * H + h) * W + w) * kBlock + c % kBlock] != 0.f)
            return false;
  return true;
}

}  // namespace yelan::test
