#include "kernels/conv_bf16.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <mutex>
#include <stdexcept>

#if defined(__x86_64__)
#include <sys/syscall.h>
#include <unistd.h>
#endif

namespace yelan::kernels {

#if defined(__x86_64__)
extern const AmxBf16Kernels amx_bf16_kernels;  // conv_bf16_amx.cpp, compiled with AMX flags
#endif

bool amx_bf16_available() {
#if defined(__x86_64__) && defined(__linux__)
  static const bool granted = [] {
    const CpuFeatures& f = cpu_features();
    if (!f.amx_tile || !f.amx_bf16 || !f.avx512bf16 || !f.avx512f || !f.avx512bw) return false;
    // Linux hands out the 8 KB of tile state only on request (ARCH_REQ_XCOMP_PERM for
    // XFEATURE_XTILEDATA), once for the whole process and every thread it starts.
    constexpr long kReqXcompPerm = 0x1023, kXtileData = 18;
    return syscall(SYS_arch_prctl, kReqXcompPerm, kXtileData) == 0;
  }();
  return granted;
#else
  return false;
#endif
}

bool amx_bf16_enabled() { return amx_bf16_available() && active_isa() == Isa::avx512; }

bool conv_bf16_applicable(const ConvShape& s) { return s.valid() && s.stride == 1; }

namespace {
int pairs(const ConvShape& s) { return (s.icb() + 1) / 2; }
}  // namespace

std::size_t conv_bf16_weight_halves(const ConvShape& s) {
  return std::size_t(s.ocb()) * pairs(s) * s.kh * s.kw * 16 * 32;
}

void pack_conv_bf16_weights(const ConvShape& s, const float* w, std::uint16_t* out) {
  std::memset(out, 0, conv_bf16_weight_halves(s) * sizeof(std::uint16_t));
  const int ICP = pairs(s);
  for (int o = 0; o < s.oc; ++o)
    for (int i = 0; i < s.ic; ++i)
      for (int y = 0; y < s.kh; ++y)
        for (int x = 0; x < s.kw; ++x) {
          const int ob = o / kBlock, n = o % kBlock, ip = i / 32, k = i % 32;
          // tile row k/2 holds input channels k and k+1 of all 16 outputs, interleaved
          const std::size_t tile = ((std::size_t(ob) * ICP + ip) * s.kh + y) * s.kw + x;
          out[tile * 512 + (k / 2) * 32 + n * 2 + k % 2] = to_bf16(w[((std::size_t(o) * s.ic + i) * s.kh + y) * s.kw + x]);
        }
}

std::uint16_t to_bf16(float v) {
  std::uint32_t b;
  std::memcpy(&b, &v, 4);
  if ((b & 0x7f800000u) == 0) return std::uint16_t((b >> 16) & 0x8000u);  // zero and subnormals
  if ((b & 0x7fffffffu) > 0x7f800000u) return std::uint16_t((b >> 16) | 0x40u);  // NaN stays NaN
  b += 0x7fffu + ((b >> 16) & 1u);
  return std::uint16_t(b >> 16);
}

float from_bf16(std::uint16_t h) {
  const std::uint32_t b = std::uint32_t(h) << 16;
  float v;
  std::memcpy(&v, &b, 4);
  return v;
}

void conv_fwd_bf16_reference(const ConvShape& s, const float* x, const float* w, const float* bias, float* y) {
  const int OH = s.oh(), OW = s.ow(), ICB = s.icb(), OCB = s.ocb();
  std::memset(y, 0, std::size_t(s.n) * OCB * OH * OW * kBlock * sizeof(float));
  auto bf = [](float v) { return double(from_bf16(to_bf16(v))); };
  for (int n = 0; n < s.n; ++n)
    for (int o = 0; o < s.oc; ++o)
      for (int oh = 0; oh < OH; ++oh)
        for (int ow = 0; ow < OW; ++ow) {
          double acc = bias ? bias[o] : 0.0;
          for (int i = 0; i < s.ic; ++i)
            for (int ky = 0; ky < s.kh; ++ky)
              for (int kx = 0; kx < s.kw; ++kx) {
                const int ih = oh * s.stride + ky - s.pad_h, iw = ow * s.stride + kx - s.pad_w;
                if (ih < 0 || ih >= s.ih || iw < 0 || iw >= s.iw) continue;
                const float xv = x[(((std::size_t(n) * ICB + i / kBlock) * s.ih + ih) * s.iw + iw) * kBlock + i % kBlock];
                acc += bf(xv) * bf(w[((std::size_t(o) * s.ic + i) * s.kh + ky) * s.kw + kx]);
              }
          if (s.relu) acc = std::max(acc, 0.0);
          y[(((std::size_t(n) * OCB + o / kBlock) * OH + oh) * OW + ow) * kBlock + o % kBlock] = float(acc);
        }
}

void conv_fwd_bf16_amx(const ConvShape& s, const float* x, const std::uint16_t* w, const float* bias, float* y) {
  if (!conv_bf16_applicable(s)) throw std::invalid_argument("conv_fwd_bf16_amx: stride 1 convolutions only");
  if (!amx_bf16_available()) throw std::logic_error("conv_fwd_bf16_amx: this CPU or OS gives no AMX-BF16");
#if defined(__x86_64__)
  amx_bf16_kernels.conv(s, x, w, bias, y);
#else
  (void)x; (void)w; (void)bias; (void)y;
#endif
}

bool deconv2x2_bf16_applicable(const DeconvShape& d) {
  return d.valid() && d.kh == 2 && d.kw == 2 && d.stride == 2 && d.pad_h == 0 && d.pad_w == 0 && d.out_pad_h == 0 &&
         d.out_pad_w == 0;
}

std::size_t deconv2x2_bf16_weight_halves(const DeconvShape& d) {
  const int ICB = (d.ic + kBlock - 1) / kBlock, OCB = (d.oc + kBlock - 1) / kBlock;
  return std::size_t(4) * OCB * ((ICB + 1) / 2) * 512;
}

void pack_deconv2x2_bf16_weights(const DeconvShape& d, const float* w, std::uint16_t* out) {
  std::memset(out, 0, deconv2x2_bf16_weight_halves(d) * sizeof(std::uint16_t));
  const int ICB = (d.ic + kBlock - 1) / kBlock, OCB = (d.oc + kBlock - 1) / kBlock, ICP = (ICB + 1) / 2;
  for (int i = 0; i < d.ic; ++i)
    for (int o = 0; o < d.oc; ++o)
      for (int phase = 0; phase < 4; ++phase) {
        const int nb = phase * OCB + o / kBlock, n = o % kBlock, ip = i / 32, k = i % 32;
        const std::size_t tile = std::size_t(nb) * ICP + ip;
        out[tile * 512 + (k / 2) * 32 + n * 2 + k % 2] = to_bf16(w[(std::size_t(i) * d.oc + o) * 4 + phase]);
      }
}

void deconv2x2_fwd_bf16_reference(const DeconvShape& d, const float* x, const float* w, const float* bias, float* y) {
  const int ICB = (d.ic + kBlock - 1) / kBlock, OCB = (d.oc + kBlock - 1) / kBlock, OH = d.oh(), OW = d.ow();
  std::memset(y, 0, std::size_t(d.n) * OCB * OH * OW * kBlock * sizeof(float));
  auto bf = [](float v) { return double(from_bf16(to_bf16(v))); };
  for (int n = 0; n < d.n; ++n)
    for (int o = 0; o < d.oc; ++o)
      for (int oh = 0; oh < OH; ++oh)
        for (int ow = 0; ow < OW; ++ow) {
          const int h = oh / 2, w_ = ow / 2, phase = (oh % 2) * 2 + ow % 2;
          double acc = bias ? bias[o] : 0.0;
          for (int i = 0; i < d.ic; ++i)
            acc += bf(x[(((std::size_t(n) * ICB + i / kBlock) * d.ih + h) * d.iw + w_) * kBlock + i % kBlock]) *
                   bf(w[(std::size_t(i) * d.oc + o) * 4 + phase]);
          y[(((std::size_t(n) * OCB + o / kBlock) * OH + oh) * OW + ow) * kBlock + o % kBlock] = float(acc);
        }
}

void deconv2x2_fwd_bf16_amx(const DeconvShape& d, const float* x, const std::uint16_t* w, const float* bias, float* y) {
  if (!deconv2x2_bf16_applicable(d))
    throw std::invalid_argument("deconv2x2_fwd_bf16_amx: 2x2 stride-2 transposed convolutions without padding only");
  if (!amx_bf16_available()) throw std::logic_error("deconv2x2_fwd_bf16_amx: this CPU or OS gives no AMX-BF16");
#if defined(__x86_64__)
  amx_bf16_kernels.deconv2x2(d, x, w, bias, y);
#else
  (void)x; (void)w; (void)bias; (void)y;
#endif
}

}  // namespace yelan::kernels
