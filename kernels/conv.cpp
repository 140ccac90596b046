#include "kernels/conv.h"

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <new>
#include <stdexcept>
#include <vector>

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

float* thread_scratch(std::size_t floats) {
  struct Scratch {
    float* p = nullptr;
    std::size_t n = 0;
    ~Scratch() { std::free(p); }
  };
  thread_local Scratch s;
  if (s.n < floats) {
    std::free(s.p);
    s.n = 0;
    s.p = static_cast<float*>(std::aligned_alloc(64, (floats * sizeof(float) + 63) / 64 * 64));
    if (!s.p) throw std::bad_alloc();
    s.n = floats;
  }
  return s.p;
}

bool winograd_applicable(const ConvShape& s) { return s.valid() && s.kh == 3 && s.kw == 3 && s.stride == 1; }

bool winograd_pays(const ConvShape& s) {
  const int tiles = ((s.oh() + 3) / 4) * ((s.ow() + 3) / 4) * s.n;
  const int channels = std::min(s.ic, s.oc);
  return winograd_applicable(s) && channels >= 16 && (tiles >= 24 || channels >= 64);
}

std::size_t winograd_weight_floats(const ConvShape& s) { return 36 * std::size_t(s.ocb()) * s.icb() * kBlock * kBlock; }

void pack_winograd_weights(const ConvShape& s, const float* w, float* out) {
  static const double G[6][3] = {{1.0 / 4, 0, 0},           {-1.0 / 6, -1.0 / 6, -1.0 / 6}, {-1.0 / 6, 1.0 / 6, -1.0 / 6},
                                 {1.0 / 24, 1.0 / 12, 1.0 / 6}, {1.0 / 24, -1.0 / 12, 1.0 / 6}, {0, 0, 1}};
  std::memset(out, 0, winograd_weight_floats(s) * sizeof(float));
  const int OCB = s.ocb(), ICB = s.icb();
  for (int o = 0; o < s.oc; ++o)
    for (int i = 0; i < s.ic; ++i) {
      const float* g = w + (std::size_t(o) * s.ic + i) * 9;
      double gg[6][3];  // G g
      for (int a = 0; a < 6; ++a)
        for (int c = 0; c < 3; ++c) gg[a][c] = G[a][0] * g[c] + G[a][1] * g[3 + c] + G[a][2] * g[6 + c];
      for (int a = 0; a < 6; ++a)
        for (int b = 0; b < 6; ++b) {
          const double u = gg[a][0] * G[b][0] + gg[a][1] * G[b][1] + gg[a][2] * G[b][2];  // (G g) G^T
          out[((((std::size_t(a * 6 + b) * OCB + o / kBlock) * ICB + i / kBlock) * kBlock + i % kBlock) * kBlock) +
              o % kBlock] = float(u);
        }
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

// The reference's one loop nest: out(n, o, oh, ow) once per output, then tap(i, ih, iw, kh,
// kw) for every input channel and kernel tap that lands inside the image, in plain order.
template <class Out, class Tap>
void for_each_output_tap(const ConvShape& s, Out&& out, Tap&& tap) {
  for (int n = 0; n < s.n; ++n)
    for (int o = 0; o < s.oc; ++o)
      for (int oh = 0; oh < s.oh(); ++oh)
        for (int ow = 0; ow < s.ow(); ++ow) {
          out(n, o, oh, ow);
          for (int i = 0; i < s.ic; ++i)
            for (int kh = 0; kh < s.kh; ++kh) {
              const int ih = oh * s.stride - s.pad_h + kh;
              if (ih < 0 || ih >= s.ih) continue;
              for (int kw = 0; kw < s.kw; ++kw) {
                const int iw = ow * s.stride - s.pad_w + kw;
                if (iw >= 0 && iw < s.iw) tap(i, ih, iw, kh, kw);
              }
            }
        }
}

void relu_if_asked(const ConvShape& s, float* y) {
  if (!s.relu) return;
  for (std::size_t i = 0, n = y_floats(s); i < n; ++i) y[i] = y[i] > 0.f ? y[i] : 0.f;
}

void fwd_scalar(const ConvShape& s, const float* x, const float* w, const float* bias, float* y) {
  const Blocked b{s};
  std::memset(y, 0, y_floats(s) * sizeof(float));
  int n = 0, o = 0;
  float* dst = nullptr;
  for_each_output_tap(
      s,
      [&](int n_, int o_, int oh, int ow) {
        n = n_, o = o_;
        dst = &y[b.y(n, o, oh, ow)];
        *dst = bias ? bias[o] : 0.f;
      },
      [&](int i, int ih, int iw, int kh, int kw) { *dst += x[b.x(n, i, ih, iw)] * w[b.wf(o, i, kh, kw)]; });
  relu_if_asked(s, y);
}

void bwd_data_scalar(const ConvShape& s, const float* dy, const float* w, const float* bias, float* dx) {
  const Blocked b{s};
  std::memset(dx, 0, x_floats(s) * sizeof(float));
  if (bias)
    for (int n = 0; n < s.n; ++n)
      for (int i = 0; i < s.ic; ++i)
        for (int h = 0; h < s.ih; ++h)
          for (int w = 0; w < s.iw; ++w) dx[b.x(n, i, h, w)] = bias[i];
  int n = 0, o = 0;
  float g = 0;
  for_each_output_tap(
      s, [&](int n_, int o_, int oh, int ow) { n = n_, o = o_, g = dy[b.y(n, o, oh, ow)]; },
      [&](int i, int ih, int iw, int kh, int kw) { dx[b.x(n, i, ih, iw)] += g * w[b.wb(o, i, kh, kw)]; });
}

void bwd_weights_scalar(const ConvShape& s, const float* x, const float* dy, float* dw, float* dbias) {
  const Blocked b{s};
  std::memset(dw, 0, conv_weight_floats(s) * sizeof(float));
  if (dbias) std::memset(dbias, 0, std::size_t(s.ocb()) * kBlock * sizeof(float));
  std::vector<double> bias_sum(s.oc, 0.0);
  int n = 0, o = 0;
  float g = 0;
  for_each_output_tap(
      s,
      [&](int n_, int o_, int oh, int ow) {
        n = n_, o = o_, g = dy[b.y(n, o, oh, ow)];
        bias_sum[o] += g;
      },
      [&](int i, int ih, int iw, int kh, int kw) { dw[b.wf(o, i, kh, kw)] += g * x[b.x(n, i, ih, iw)]; });
  if (dbias)
    for (int o = 0; o < s.oc; ++o) dbias[o] = float(bias_sum[o]);
}

// Winograd by the textbook, one output channel and one tile at a time (the reference the
// SIMD variants are checked against, besides the direct convolution).
void fwd_winograd_scalar(const ConvShape& s, const float* x, const float* u, const float* bias, float* y) {
  fwd_winograd_scalar_rounded(s, x, u, bias, y, [](float v) { return v; });
}

// The scalar table's: the two copied into one map, then the textbook Winograd.
void fwd_winograd_cat_scalar(const ConvShape& s, const ConcatInput& in, const float* u, const float* bias, float* y) {
  std::vector<float> x(x_floats(s));
  concat_input(s, in, x.data());
  fwd_winograd_scalar(s, x.data(), u, bias, y);
}

}  // namespace

bool winograd_cat_applicable(const ConvShape& s, const ConcatInput& in) {
  // The input's blocks past a must lie within b's: else an 8-lane vector of the input's last
  // block would read past b's storage (a_c % 16 == 8 with b's last block more than half full).
  const int lanes_past_a = s.icb() * kBlock - in.a_c, b_lanes = (in.b_c + kBlock - 1) / kBlock * kBlock;
  return winograd_applicable(s) && s.n == 1 && in.a && in.b && in.a_c > 0 && in.b_c > 0 && in.a_c % 8 == 0 &&
         s.ic == in.a_c + in.b_c && lanes_past_a <= b_lanes && in.top >= 0 && in.left >= 0 && in.b_h > 0 &&
         in.b_w > 0 && in.top + in.b_h <= s.ih && in.left + in.b_w <= s.iw;
}

void concat_input(const ConvShape& s, const ConcatInput& in, float* x) {
  if (!winograd_cat_applicable(s, in)) throw std::invalid_argument("concat_input: the two maps do not make the input");
  const std::size_t plane = std::size_t(s.ih) * s.iw, b_plane = std::size_t(in.b_h) * in.b_w;
  std::memset(x, 0, x_floats(s) * sizeof(float));
  for (int c = 0; c < s.ic; ++c) {
    float* dst = x + std::size_t(c / kBlock) * plane * kBlock + c % kBlock;
    for (int h = 0; h < s.ih; ++h)
      for (int w = 0; w < s.iw; ++w) {
        float v = 0;
        if (c < in.a_c) {
          v = in.a[(std::size_t(c / kBlock) * plane + std::size_t(h) * s.iw + w) * kBlock + c % kBlock];
        } else {
          const int cb = c - in.a_c, bh = h - in.top, bw = w - in.left;
          if (bh >= 0 && bh < in.b_h && bw >= 0 && bw < in.b_w)
            v = in.b[(std::size_t(cb / kBlock) * b_plane + std::size_t(bh) * in.b_w + bw) * kBlock + cb % kBlock];
        }
        dst[(std::size_t(h) * s.iw + w) * kBlock] = v;
      }
  }
}

void fwd_winograd_scalar_rounded(const ConvShape& s, const float* x, const float* u, const float* bias, float* y,
                                 float (*round_v)(float)) {
  static const float BT[6][6] = {{4, 0, -5, 0, 1, 0},  {0, -4, -4, 1, 1, 0}, {0, 4, -4, -1, 1, 0},
                                 {0, -2, -1, 2, 1, 0}, {0, 2, -1, -2, 1, 0}, {0, 4, 0, -5, 0, 1}};
  static const float AT[4][6] = {{1, 1, 1, 1, 1, 0}, {0, 1, -1, 2, -2, 0}, {0, 1, 1, 4, 4, 0}, {0, 1, -1, 8, -8, 1}};
  const Blocked b{s};
  const int OH = s.oh(), OW = s.ow(), OCB = s.ocb(), ICB = s.icb();
  for (int n = 0; n < s.n; ++n)
    for (int th = 0; th < OH; th += 4)
      for (int tw = 0; tw < OW; tw += 4)
        for (int o = 0; o < s.oc; ++o) {
          float m[6][6] = {};
          for (int i = 0; i < s.ic; ++i) {
            float d[6][6], t[6][6];
            for (int r = 0; r < 6; ++r)
              for (int c = 0; c < 6; ++c) {
                const int ih = th - s.pad_h + r, iw = tw - s.pad_w + c;
                d[r][c] = ih >= 0 && ih < s.ih && iw >= 0 && iw < s.iw ? x[b.x(n, i, ih, iw)] : 0.f;
              }
            for (int r = 0; r < 6; ++r)
              for (int c = 0; c < 6; ++c) {
                t[r][c] = 0;
                for (int k = 0; k < 6; ++k) t[r][c] += BT[r][k] * d[k][c];
              }
            for (int r = 0; r < 6; ++r)
              for (int c = 0; c < 6; ++c) {
                float v = 0;
                for (int k = 0; k < 6; ++k) v += t[r][k] * BT[c][k];
                m[r][c] += round_v(v) * u[((((std::size_t(r * 6 + c) * OCB + o / kBlock) * ICB + i / kBlock) * kBlock +
                                   i % kBlock) * kBlock) + o % kBlock];
              }
          }
          for (int r = 0; r < 4 && th + r < OH; ++r)
            for (int c = 0; c < 4 && tw + c < OW; ++c) {
              float v = bias ? bias[o] : 0.f;
              for (int a = 0; a < 6; ++a)
                for (int k = 0; k < 6; ++k) v += AT[r][a] * m[a][k] * AT[c][k];
              y[b.y(n, o, th + r, tw + c)] = v;
            }
        }
  // padding lanes of y stay zero
  for (int n = 0; n < s.n; ++n)
    for (int o = s.oc; o < OCB * kBlock; ++o)
      for (int h = 0; h < OH; ++h)
        for (int w = 0; w < OW; ++w) y[b.y(n, o, h, w)] = 0.f;
  relu_if_asked(s, y);
}

namespace {

// Sums per channel of a blocked [n][cb][pixels][16] array.
void channel_sums(int n, int cb, std::size_t pixels, const float* x, float* sums) {
  for (int b = 0; b < cb; ++b) {
    double total[kBlock] = {};
    for (int i = 0; i < n; ++i) {
      const float* p = x + (std::size_t(i) * cb + b) * pixels * kBlock;
      for (std::size_t px = 0; px < pixels; ++px)
        for (int l = 0; l < kBlock; ++l) total[l] += p[px * kBlock + l];
    }
    for (int l = 0; l < kBlock; ++l) sums[b * kBlock + l] = float(total[l]);
  }
}

}  // namespace

void deconv_fwd(const ConvKernels& k, const DeconvShape& s, const float* x, const float* w_bwd, const float* bias,
                float* y) {
  const ConvShape c = s.as_conv();
  k.bwd_data(c, x, w_bwd, bias, y);
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

const ConvKernels conv_scalar{Isa::scalar,         fwd_scalar,         bwd_data_scalar, bwd_weights_scalar,
                              fwd_winograd_scalar, fwd_winograd_cat_scalar};

YELAN_KERNEL_DISPATCH(ConvKernels, conv)

}  // namespace yelan::kernels
