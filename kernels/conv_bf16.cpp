#include "kernels/conv_bf16.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <vector>

// YELAN_AMX_BUILT: kernels/CMakeLists.txt compiled conv_bf16_amx.cpp (an x86-64 compiler
// that takes -mamx-tile and -mamx-bf16); without it there is no AMX path to call.
#if defined(YELAN_AMX_BUILT)
#include <sys/syscall.h>
#include <unistd.h>
#endif

namespace yelan::kernels {

#if defined(YELAN_AMX_BUILT)
extern const AmxBf16Kernels amx_bf16_kernels;  // conv_bf16_amx.cpp, compiled with AMX flags
#endif
#if defined(YELAN_WINOGRAD_BF16_BUILT)
extern const WinogradBf16Kernels winograd_bf16_kernels;  // conv_winograd_bf16.cpp, AVX512-BF16 flags
#endif

bool amx_bf16_available() {
#if defined(YELAN_AMX_BUILT) && defined(__linux__)
  static const bool granted = [] {
    const CpuFeatures& f = cpu_features();
    if (!f.amx_tile || !f.amx_bf16 || !f.avx512bf16 || !f.avx512f || !f.avx512bw || !f.avx512vl) return false;
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

bool winograd_bf16_available() {
#if defined(YELAN_WINOGRAD_BF16_BUILT)
  const CpuFeatures& f = cpu_features();
  // The file is built with the avx512 variant's flags (FMA, AVX2, F16C among them) and -mavx512bf16.
  return f.avx512f && f.avx512bw && f.avx512vl && f.avx512dq && f.avx2 && f.fma && f.f16c && f.avx512bf16;
#else
  return false;
#endif
}

bool winograd_bf16_enabled() { return winograd_bf16_available() && active_isa() == Isa::avx512; }

bool winograd_bf16_pays(const ConvShape& s) {
  const int tiles = ((s.oh() + 3) / 4) * ((s.ow() + 3) / 4) * s.n;
  return winograd_pays(s) || (winograd_applicable(s) && s.oc >= 16 && tiles >= 24);
}

std::size_t winograd_bf16_weight_halves(const ConvShape& s) { return winograd_weight_floats(s); }

void pack_winograd_bf16_weights(const ConvShape& s, const float* u, std::uint16_t* out) {
  const std::size_t blocks = winograd_weight_floats(s) / (kBlock * kBlock);  // [36][OCB][ICB]
  for (std::size_t b = 0; b < blocks; ++b)
    for (int k = 0; k < kBlock; ++k)
      for (int n = 0; n < kBlock; ++n)
        out[b * kBlock * kBlock + bf16_tile_index(k, n)] = to_bf16(u[(b * kBlock + k) * kBlock + n]);
}

void conv_fwd_winograd_bf16(const ConvShape& s, const float* x, const std::uint16_t* u, const float* bias, float* y) {
  if (!winograd_applicable(s)) throw std::invalid_argument("conv_fwd_winograd_bf16: 3x3 stride 1 convolutions only");
  if (!winograd_bf16_available()) throw std::logic_error("conv_fwd_winograd_bf16: this CPU gives no AVX512-BF16");
#if defined(YELAN_WINOGRAD_BF16_BUILT)
  winograd_bf16_kernels.fwd(s, x, u, bias, y);
#else
  (void)x; (void)u; (void)bias; (void)y;
#endif
}

void conv_fwd_winograd_bf16_cat(const ConvShape& s, const ConcatInput& in, const std::uint16_t* u, const float* bias,
                                float* y) {
  if (!winograd_cat_applicable(s, in)) throw std::invalid_argument("conv_fwd_winograd_bf16_cat: not a concatenated 3x3/1 input");
  if (!winograd_bf16_available()) throw std::logic_error("conv_fwd_winograd_bf16_cat: this CPU gives no AVX512-BF16");
#if defined(YELAN_WINOGRAD_BF16_BUILT)
  winograd_bf16_kernels.fwd_cat(s, in, u, bias, y);
#else
  (void)u; (void)bias; (void)y;
#endif
}

bool conv_bf16_applicable(const ConvShape& s) { return s.valid() && s.stride == 1; }

std::size_t conv_bf16_weight_halves(const ConvShape& s) {
  return std::size_t(s.ocb()) * bf16_pairs(s.icb()) * s.kh * s.kw * 16 * 32;
}

void pack_conv_bf16_weights(const ConvShape& s, const float* w, std::uint16_t* out) {
  std::memset(out, 0, conv_bf16_weight_halves(s) * sizeof(std::uint16_t));
  const int ICP = bf16_pairs(s.icb());
  for (int o = 0; o < s.oc; ++o)
    for (int i = 0; i < s.ic; ++i)
      for (int y = 0; y < s.kh; ++y)
        for (int x = 0; x < s.kw; ++x) {
          const int ob = o / kBlock, n = o % kBlock, ip = i / 32, k = i % 32;
          const std::size_t tile = ((std::size_t(ob) * ICP + ip) * s.kh + y) * s.kw + x;
          out[tile * 512 + bf16_tile_index(k, n)] = to_bf16(w[((std::size_t(o) * s.ic + i) * s.kh + y) * s.kw + x]);
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

namespace {
std::vector<float> rounded_to_bf16(const float* v, std::size_t n) {
  std::vector<float> r(n);
  for (std::size_t i = 0; i < n; ++i) r[i] = from_bf16(to_bf16(v[i]));
  return r;
}
}  // namespace

// The references are the scalar fp32 kernels on the rounded operands: what the tiles compute
// up to the order of the fp32 sums.
void conv_fwd_bf16_reference(const ConvShape& s, const float* x, const float* w, const float* bias, float* y) {
  const auto xr = rounded_to_bf16(x, std::size_t(s.n) * s.icb() * s.ih * s.iw * kBlock);
  const auto wr = rounded_to_bf16(w, std::size_t(s.oc) * s.ic * s.kh * s.kw);
  std::vector<float> wp(conv_weight_floats(s));
  pack_conv_weights(s, wr.data(), ConvPack::fwd, wp.data());
  conv_scalar.fwd(s, xr.data(), wp.data(), bias, y);
}

void conv_fwd_winograd_bf16_reference(const ConvShape& s, const float* x, const float* w, const float* bias,
                                      float* y) {
  std::vector<float> u(winograd_weight_floats(s));
  pack_winograd_weights(s, w, u.data());
  for (float& v : u) v = from_bf16(to_bf16(v));
  fwd_winograd_scalar_rounded(s, x, u.data(), bias, y, [](float v) { return from_bf16(to_bf16(v)); });
}

void deconv2x2_fwd_bf16_reference(const DeconvShape& d, const float* x, const float* w, const float* bias, float* y) {
  const ConvShape c = d.as_conv();  // the deconv is this conv's backward-data
  const auto xr = rounded_to_bf16(x, std::size_t(d.n) * d.icb() * d.ih * d.iw * kBlock);
  const auto wr = rounded_to_bf16(w, std::size_t(d.ic) * d.oc * d.kh * d.kw);
  std::vector<float> wp(conv_weight_floats(c));
  pack_conv_weights(c, wr.data(), ConvPack::bwd_data, wp.data());
  conv_scalar.bwd_data(c, xr.data(), wp.data(), bias, y);
}

void conv_fwd_bf16_amx(const ConvShape& s, const float* x, const std::uint16_t* w, const float* bias, float* y) {
  if (!conv_bf16_applicable(s)) throw std::invalid_argument("conv_fwd_bf16_amx: stride 1 convolutions only");
  if (!amx_bf16_available()) throw std::logic_error("conv_fwd_bf16_amx: this CPU or OS gives no AMX-BF16");
#if defined(YELAN_AMX_BUILT)
  amx_bf16_kernels.conv(s, x, w, bias, y);
#else
  (void)x; (void)w; (void)bias; (void)y;
#endif
}

bool conv_bf16_cat_applicable(const ConvShape& s, const ConcatInput& in) {
  return conv_bf16_applicable(s) && s.n == 1 && in.a && in.b && in.a_c > 0 && in.b_c > 0 && in.a_c % 8 == 0 &&
         s.ic == in.a_c + in.b_c && in.top >= 0 && in.left >= 0 && in.b_h > 0 && in.b_w > 0 &&
         in.top + in.b_h <= s.ih && in.left + in.b_w <= s.iw;
}

void conv_fwd_bf16_amx_cat(const ConvShape& s, const ConcatInput& in, const std::uint16_t* w, const float* bias,
                           float* y) {
  if (!conv_bf16_cat_applicable(s, in))
    throw std::invalid_argument("conv_fwd_bf16_amx_cat: the two maps do not make a stride-1 input of one image");
  if (!amx_bf16_available()) throw std::logic_error("conv_fwd_bf16_amx_cat: this CPU or OS gives no AMX-BF16");
#if defined(YELAN_AMX_BUILT)
  amx_bf16_kernels.conv_cat(s, in, w, bias, y);
#else
  (void)w; (void)bias; (void)y;
#endif
}

bool conv_bf16_pair_applicable(const ConvShape& s1, const ConvShape& s2) {
  return conv_bf16_applicable(s1) && conv_bf16_applicable(s2) && s2.n == s1.n && s2.ic == s1.oc &&
         s2.ih == s1.oh() && s2.iw == s1.ow();
}

void conv_pair_fwd_bf16_amx(const ConvShape& s1, const ConcatInput& in, const std::uint16_t* w1, const float* bias1,
                            const ConvShape& s2, const std::uint16_t* w2, const float* bias2, float* y) {
  if (!conv_bf16_pair_applicable(s1, s2))
    throw std::invalid_argument("conv_pair_fwd_bf16_amx: two stride-1 convolutions, the second taking the first's output");
  if (in.b ? !conv_bf16_cat_applicable(s1, in) : !in.a || in.a_c != s1.ic)
    throw std::invalid_argument("conv_pair_fwd_bf16_amx: the input does not make the first convolution's");
  if (!amx_bf16_available()) throw std::logic_error("conv_pair_fwd_bf16_amx: this CPU or OS gives no AMX-BF16");
#if defined(YELAN_AMX_BUILT)
  amx_bf16_kernels.conv_pair(s1, in, w1, bias1, s2, w2, bias2, y);
#else
  (void)w1; (void)bias1; (void)w2; (void)bias2; (void)y;
#endif
}

bool deconv2x2_bf16_applicable(const DeconvShape& d) {
  return d.valid() && d.kh == 2 && d.kw == 2 && d.stride == 2 && d.pad_h == 0 && d.pad_w == 0 && d.out_pad_h == 0 &&
         d.out_pad_w == 0;
}

std::size_t deconv2x2_bf16_weight_halves(const DeconvShape& d) {
  return std::size_t(4) * d.ocb() * bf16_pairs(d.icb()) * 512;
}

void pack_deconv2x2_bf16_weights(const DeconvShape& d, const float* w, std::uint16_t* out) {
  std::memset(out, 0, deconv2x2_bf16_weight_halves(d) * sizeof(std::uint16_t));
  const int OCB = d.ocb(), ICP = bf16_pairs(d.icb());
  for (int i = 0; i < d.ic; ++i)
    for (int o = 0; o < d.oc; ++o)
      for (int phase = 0; phase < 4; ++phase) {
        const int nb = phase * OCB + o / kBlock, n = o % kBlock, ip = i / 32, k = i % 32;
        const std::size_t tile = std::size_t(nb) * ICP + ip;
        out[tile * 512 + bf16_tile_index(k, n)] = to_bf16(w[(std::size_t(i) * d.oc + o) * 4 + phase]);
      }
}

void deconv2x2_fwd_bf16_amx(const DeconvShape& d, const float* x, const std::uint16_t* w, const float* bias, float* y) {
  if (!deconv2x2_bf16_applicable(d))
    throw std::invalid_argument("deconv2x2_fwd_bf16_amx: 2x2 stride-2 transposed convolutions without padding only");
  if (!amx_bf16_available()) throw std::logic_error("deconv2x2_fwd_bf16_amx: this CPU or OS gives no AMX-BF16");
#if defined(YELAN_AMX_BUILT)
  amx_bf16_kernels.deconv2x2(d, x, w, bias, y);
#else
  (void)x; (void)w; (void)bias; (void)y;
#endif
}

std::size_t deconv2x2_bf16_pairs_weight_halves(const DeconvShape& d) {
  return std::size_t(4) * d.ocb() * d.icb() * kBlock * kBlock;
}

void pack_deconv2x2_bf16_pairs_weights(const DeconvShape& d, const float* w, std::uint16_t* out) {
  std::memset(out, 0, deconv2x2_bf16_pairs_weight_halves(d) * sizeof(std::uint16_t));
  const int OCB = d.ocb(), ICB = d.icb();
  for (int i = 0; i < d.ic; ++i)
    for (int o = 0; o < d.oc; ++o)
      for (int phase = 0; phase < 4; ++phase) {
        const std::size_t block = (std::size_t(phase) * OCB + o / kBlock) * ICB + i / kBlock;
        out[block * kBlock * kBlock + bf16_tile_index(i % kBlock, o % kBlock)] =
            to_bf16(w[(std::size_t(i) * d.oc + o) * 4 + phase]);
      }
}

void deconv2x2_fwd_bf16_pairs(const DeconvShape& d, const float* x, const std::uint16_t* w, const float* bias,
                              float* y) {
  if (!deconv2x2_bf16_applicable(d))
    throw std::invalid_argument("deconv2x2_fwd_bf16_pairs: 2x2 stride-2 transposed convolutions without padding only");
  if (!winograd_bf16_available()) throw std::logic_error("deconv2x2_fwd_bf16_pairs: this CPU gives no AVX512-BF16");
#if defined(YELAN_WINOGRAD_BF16_BUILT)
  winograd_bf16_kernels.deconv2x2(d, x, w, bias, y);
#else
  (void)x; (void)w; (void)bias; (void)y;
#endif
}

}  // namespace yelan::kernels
