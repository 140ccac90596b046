#include "kernels/conv.h"

#include <algorithm>
#include <cstring>

#include "kernels/dispatch.h"

namespace yelan::kernels {

bool ConvShape::valid() const {
  return n > 0 && ic > 0 && ih > 0 && iw > 0 && oc > 0 && kh > 0 && kw > 0 && stride > 0 &&
         kh <= kMaxKernel && kw <= kMaxKernel &&
         pad_h >= 0 && pad_w >= 0 && pad_h < kh && pad_w < kw && ih + 2 * pad_h >= kh &&
         iw + 2 * pad_w >= kw;
}

std::size_t conv_weight_floats(const ConvShape& s) {
  return std::size_t(s.ocb()) * s.icb() * s.kh * s.kw * kBlock * kBlock;
}

void pack_conv_weights(const ConvShape& s, const float* w, ConvPack pack, float* out) {
  std::memset(out, 0, conv_weight_floats(s) * sizeof(float));
  const int OCB = s.ocb(), ICB = s.icb();
  for (int o = 0; o < s.oc; ++o)
    for (int i = 0; i < s.ic; ++i)
      for (int y = 0; y < s.kh; ++y)
        for (int x = 0; x < s.kw; ++x) {
          const float v = w[((std::size_t(o) * s.ic + i) * s.kh + y) * s.kw + x];
          const int ob = o / kBlock, co = o % kBlock, cb = i / kBlock, ci = i % kBlock;
          std::size_t at;
          if (pack == ConvPack::fwd)
            at = ((((std::size_t(ob) * ICB + cb) * s.kh + y) * s.kw + x) * kBlock + ci) * kBlock + co;
          else
            at = ((((std::size_t(cb) * OCB + ob) * s.kh + y) * s.kw + x) * kBlock + co) * kBlock + ci;
          out[at] = v;
        }
}

void unpack_conv_weights(const ConvShape& s, const float* p, float* w) {
  const int ICB = s.icb();
  for (int o = 0; o < s.oc; ++o)
    for (int i = 0; i < s.ic; ++i)
      for (int y = 0; y < s.kh; ++y)
        for (int x = 0; x < s.kw; ++x) {
          const int ob = o / kBlock, co = o % kBlock, cb = i / kBlock, ci = i % kBlock;
          w[((std::size_t(o) * s.ic + i) * s.kh + y) * s.kw + x] =
              p[((((std::size_t(ob) * ICB + cb) * s.kh + y) * s.kw + x) * kBlock + ci) * kBlock + co];
        }
}

namespace {

// Plain loops over the blocked layout: the reference the SIMD variants are tested against.
struct Blocked {
  const ConvShape& s;
  std::size_t x(int n, int c, int h, int w) const {
    return ((((std::size_t(n) * s.icb() + c / kBlock) * s.ih + h) * s.iw + w) * kBlock) + c % kBlock;
  }
  std::size_t y(int n, int c, int h, int w) const {
    return ((((std::size_t(n) * s.ocb() + c / kBlock) * s.oh() + h) * s.ow() + w) * kBlock) + c % kBlock;
  }
  std::size_t wf(int o, int i, int h, int w) const {
    return ((((std::size_t(o / kBlock) * s.icb() + i / kBlock) * s.kh + h) * s.kw + w) * kBlock + i % kBlock) *
               kBlock + o % kBlock;
  }
  std::size_t wb(int o, int i, int h, int w) const {
    return ((((std::size_t(i / kBlock) * s.ocb() + o / kBlock) * s.kh + h) * s.kw + w) * kBlock + o % kBlock) *
               kBlock + i % kBlock;
  }
};

std::size_t x_floats(const ConvShape& s) { return std::size_t(s.n) * s.icb() * s.ih * s.iw * kBlock; }
std::size_t y_floats(const ConvShape& s) { return std::size_t(s.n) * s.ocb() * s.oh() * s.ow() * kBlock; }

void fwd_scalar(const ConvShape& s, const float* x, const float* w, const float* bias, float* y) {
  const Blocked b{s};
  std::memset(y, 0, y_floats(s) * sizeof(float));
  for (int n = 0; n < s.n; ++n)
    for (int o = 0; o < s.oc; ++o)
      for (int oh = 0; oh < s.oh(); ++oh)
        for (int ow = 0; ow < s.ow(); ++ow) {
          float acc = bias ? bias[o] : 0.f;
          for (int i = 0; i < s.ic; ++i)
            for (int kh = 0; kh < s.kh; ++kh) {
              const int ih = oh * s.stride - s.pad_h + kh;
              if (ih < 0 || ih >= s.ih) continue;
              for (int kw = 0; kw < s.kw; ++kw) {
                const int iw = ow * s.stride - s.pad_w + kw;
                if (iw < 0 || iw >= s.iw) continue;
                acc += x[b.x(n, i, ih, iw)] * w[b.wf(o, i, kh, kw)];
              }
            }
          y[b.y(n, o, oh, ow)] = acc;
        }
}

void bwd_data_scalar(const ConvShape& s, const float* dy, const float* w, float* dx) {
  const Blocked b{s};
  std::memset(dx, 0, x_floats(s) * sizeof(float));
  for (int n = 0; n < s.n; ++n)
    for (int o = 0; o < s.oc; ++o)
      for (int oh = 0; oh < s.oh(); ++oh)
        for (int ow = 0; ow < s.ow(); ++ow) {
          const float g = dy[b.y(n, o, oh, ow)];
          for (int i = 0; i < s.ic; ++i)
            for (int kh = 0; kh < s.kh; ++kh) {
              const int ih = oh * s.stride - s.pad_h + kh;
              if (ih < 0 || ih >= s.ih) continue;
              for (int kw = 0; kw < s.kw; ++kw) {
                const int iw = ow * s.stride - s.pad_w + kw;
                if (iw < 0 || iw >= s.iw) continue;
                dx[b.x(n, i, ih, iw)] += g * w[b.wb(o, i, kh, kw)];
              }
            }
        }
}

void bwd_weights_scalar(const ConvShape& s, const float* x, const float* dy, float* dw, float* dbias) {
  const Blocked b{s};
  std::memset(dw, 0, conv_weight_floats(s) * sizeof(float));
  if (dbias) std::memset(dbias, 0, std::size_t(s.ocb()) * kBlock * sizeof(float));
  for (int n = 0; n < s.n; ++n)
    for (int o = 0; o < s.oc; ++o)
      for (int oh = 0; oh < s.oh(); ++oh)
        for (int ow = 0; ow < s.ow(); ++ow) {
          const float g = dy[b.y(n, o, oh, ow)];
          if (dbias) dbias[o] += g;
          for (int i = 0; i < s.ic; ++i)
            for (int kh = 0; kh < s.kh; ++kh) {
              const int ih = oh * s.stride - s.pad_h + kh;
              if (ih < 0 || ih >= s.ih) continue;
              for (int kw = 0; kw < s.kw; ++kw) {
                const int iw = ow * s.stride - s.pad_w + kw;
                if (iw < 0 || iw >= s.iw) continue;
                dw[b.wf(o, i, kh, kw)] += g * x[b.x(n, i, ih, iw)];
              }
            }
        }
}

}  // namespace

namespace {

// Adds a per-channel bias to (or sums per channel of) a blocked [n][cb][pixels][16] array.
void add_channel_bias(int n, int cb, std::size_t pixels, const float* bias, float* y) {
  for (int i = 0; i < n; ++i)
    for (int b = 0; b < cb; ++b) {
      float* p = y + (std::size_t(i) * cb + b) * pixels * kBlock;
      for (std::size_t px = 0; px < pixels; ++px)
        for (int l = 0; l < kBlock; ++l) p[px * kBlock + l] += bias[b * kBlock + l];
    }
}
void channel_sums(int n, int cb, std::size_t pixels, const float* x, float* sums) {
  std::fill(sums, sums + std::size_t(cb) * kBlock, 0.f);
  for (int i = 0; i < n; ++i)
    for (int b = 0; b < cb; ++b) {
      const float* p = x + (std::size_t(i) * cb + b) * pixels * kBlock;
      for (std::size_t px = 0; px < pixels; ++px)
        for (int l = 0; l < kBlock; ++l) sums[b * kBlock + l] += p[px * kBlock + l];
    }
}

}  // namespace

void deconv_fwd(const ConvKernels& k, const DeconvShape& s, const float* x, const float* w_bwd, const float* bias,
                float* y) {
  const ConvShape c = s.as_conv();
  k.bwd_data(c, x, w_bwd, y);
  if (bias) add_channel_bias(s.n, c.icb(), std::size_t(c.ih) * c.iw, bias, y);
}

void deconv_bwd_data(const ConvKernels& k, const DeconvShape& s, const float* dy, const float* w_fwd, float* dx) {
  k.fwd(s.as_conv(), dy, w_fwd, nullptr, dx);
}

void deconv_bwd_weights(const ConvKernels& k, const DeconvShape& s, const float* x, const float* dy, float* dw,
                        float* dbias) {
  const ConvShape c = s.as_conv();
  k.bwd_weights(c, dy, x, dw, nullptr);
  if (dbias) channel_sums(s.n, c.icb(), std::size_t(c.ih) * c.iw, dy, dbias);
}

const ConvKernels conv_scalar{Isa::scalar, fwd_scalar, bwd_data_scalar, bwd_weights_scalar};

#if defined(__x86_64__)
extern const ConvKernels conv_avx2;
extern const ConvKernels conv_avx512;
#elif defined(__aarch64__)
extern const ConvKernels conv_neon;
#endif

const ConvKernels& conv_kernels(Isa isa) {
  Variants<ConvKernels> v;
  v.scalar = &conv_scalar;
#if defined(__x86_64__)
  v.avx2 = &conv_avx2;
  v.avx512 = &conv_avx512;
#elif defined(__aarch64__)
  v.neon = &conv_neon;
#endif
  return select_variant(v, isa);
}

}  // namespace yelan::kernels
