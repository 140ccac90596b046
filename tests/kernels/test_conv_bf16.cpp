#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>

#include "conv_reference.h"
#include "kernels/conv_bf16.h"
#include "test_util.h"

using namespace yelan::kernels;
using yelan::test::padding_is_zero;
using yelan::test::random_floats;
using yelan::test::to_blocked;

namespace {

struct Case {
  int n, ic, ih, iw, oc, k, pad;
};

ConvShape shape_of(const Case& c, bool relu) {
  ConvShape s;
  s.n = c.n; s.ic = c.ic; s.ih = c.ih; s.iw = c.iw; s.oc = c.oc;
  s.kh = s.kw = c.k; s.pad_h = s.pad_w = c.pad; s.relu = relu;
  return s;
}

// A bf16 kernel's y against its reference: every error, over `scale` (the sum of |x w| is at
// most ic k k for inputs in [-1, 1]), within `bound`; a ReLU's outputs non-negative, and
// without one some negatives (so the ReLU case is a test). Returns the worst error.
double check_against_reference(const std::vector<float>& y, const std::vector<float>& ref, double scale, double bound,
                               bool relu) {
  double worst = 0;
  int negatives = 0;
  for (std::size_t i = 0; i < y.size(); ++i) {
    const double e = std::fabs(double(y[i]) - ref[i]) / scale;
    worst = std::max(worst, e);
    REQUIRE(e <= bound);
    negatives += ref[i] < 0;
    if (relu) REQUIRE(y[i] >= 0.f);
  }
  if (!relu) CHECK(negatives > 0);
  return worst;
}

// A bf16 kernel's y against the fp32 convolution: within `bound` x scale, and different on
// most outputs (it is bf16). Returns the worst error over scale.
double check_rounded_fp32(const std::vector<float>& y, const std::vector<float>& fp32, double scale, double bound) {
  double worst = 0;
  std::size_t differ = 0;
  for (std::size_t i = 0; i < y.size(); ++i) {
    worst = std::max(worst, std::fabs(double(y[i]) - fp32[i]) / scale);
    differ += y[i] != fp32[i];
  }
  CHECK(worst <= bound);
  CHECK(differ > y.size() / 4);
  return worst;
}

}  // namespace

TEST_CASE("bf16 rounding is to nearest even, subnormals to zero, NaN kept", "[conv_bf16]") {
  CHECK(to_bf16(1.f) == 0x3f80);
  CHECK(to_bf16(-2.f) == 0xc000);
  // 1 + 2^-8 lies halfway between 1 and 1 + 2^-7: even (1) wins; 1 + 3 * 2^-8 rounds up to 1 + 2^-6
  CHECK(from_bf16(to_bf16(1.f + std::ldexp(1.f, -8))) == 1.f);
  CHECK(from_bf16(to_bf16(1.f + 3 * std::ldexp(1.f, -8))) == 1.f + std::ldexp(1.f, -6));
  CHECK(from_bf16(to_bf16(1.f + std::ldexp(1.f, -8) + std::ldexp(1.f, -20))) == 1.f + std::ldexp(1.f, -7));
  CHECK(to_bf16(std::numeric_limits<float>::denorm_min()) == 0);
  CHECK(to_bf16(-std::numeric_limits<float>::denorm_min()) == 0x8000);
  CHECK(std::isnan(from_bf16(to_bf16(std::numeric_limits<float>::quiet_NaN()))));
  CHECK(std::isinf(from_bf16(to_bf16(std::numeric_limits<float>::infinity()))));
  CHECK(from_bf16(to_bf16(std::numeric_limits<float>::max())) == std::numeric_limits<float>::infinity());  // past bf16 largest
}

TEST_CASE("conv_bf16 applies to stride 1 alone, the up-sampling to 2x2/2 unpadded, and refuses to run without AMX", "[conv_bf16]") {
  ConvShape s = shape_of({1, 8, 5, 5, 8, 3, 1}, false);
  CHECK(conv_bf16_applicable(s));
  s.stride = 2;
  CHECK_FALSE(conv_bf16_applicable(s));
  DeconvShape d;
  d.ic = d.oc = d.ih = d.iw = 3;
  d.kh = d.kw = 2;
  d.stride = 2;
  CHECK(deconv2x2_bf16_applicable(d));
  d.out_pad_h = 1;
  CHECK_FALSE(deconv2x2_bf16_applicable(d));
  d.out_pad_h = 0;
  d.pad_h = d.pad_w = 1;
  CHECK_FALSE(deconv2x2_bf16_applicable(d));
  // A narrower ISA forced (YELAN_ISA, --isa) keeps the bf16 path off, AMX or not.
  const Isa saved = active_isa();
  CHECK(amx_bf16_enabled() == (amx_bf16_available() && saved == Isa::avx512));
  if (isa_supported(Isa::avx2)) {
    set_isa(Isa::avx2);
    CHECK_FALSE(amx_bf16_enabled());
    set_isa(saved);
  }
  if (!amx_bf16_available()) {
    s.stride = 1;
    std::vector<float> x(200 * 16), y(200 * 16);
    std::vector<std::uint16_t> w(conv_bf16_weight_halves(s));
    CHECK_THROWS_AS(conv_fwd_bf16_amx(s, x.data(), w.data(), nullptr, y.data()), std::logic_error);
  }
}

// The AMX kernel against the reference on the rounded operands, on odd shapes: channel
// counts that leave half a pair (16, 48: an odd number of blocks) or a part block (6, 24, 40),
// an odd number of output blocks, maps narrower and shorter than a 32-row task, 1x1, 3x3, 5x5.
TEST_CASE("conv_bf16 on AMX equals the bf16 reference on odd shapes, with bias and fused ReLU", "[conv_bf16]") {
  yelan::test::amx_or_skip();
  const Case cases[] = {
      {1, 6, 13, 17, 24, 3, 1},  {1, 24, 9, 21, 24, 3, 1},  {1, 48, 8, 10, 48, 3, 1}, {2, 40, 7, 5, 40, 3, 1},
      {1, 16, 1, 1, 17, 1, 0},   {1, 24, 11, 12, 16, 1, 0}, {1, 33, 6, 9, 70, 5, 2},  {1, 96, 16, 21, 96, 3, 1},
      {1, 3, 2, 3, 5, 3, 1},     {1, 64, 33, 43, 32, 3, 0},
  };
  double worst = 0;
  for (const Case& c : cases)
    for (bool relu : {false, true}) {
      const ConvShape s = shape_of(c, relu);
      INFO("n " << c.n << " ic " << c.ic << " " << c.ih << "x" << c.iw << " oc " << c.oc << " k " << c.k << " pad "
                << c.pad << " relu " << relu);
      const auto x = random_floats(std::size_t(c.n) * c.ic * c.ih * c.iw, 11 + c.ic);
      const auto w = random_floats(std::size_t(c.oc) * c.ic * c.k * c.k, 23 + c.oc);
      std::vector<float> bias(std::size_t(s.ocb()) * kBlock, 0.f);
      const auto b = random_floats(std::size_t(c.oc), 5);
      std::copy(b.begin(), b.end(), bias.begin());
      const auto xb = to_blocked(x, c.n, c.ic, c.ih, c.iw);
      std::vector<std::uint16_t> wp(conv_bf16_weight_halves(s));
      pack_conv_bf16_weights(s, w.data(), wp.data());
      const std::size_t ny = std::size_t(c.n) * s.ocb() * s.oh() * s.ow() * kBlock;
      std::vector<float> y(ny, -7.f), ref(ny);
      conv_fwd_bf16_amx(s, xb.data(), wp.data(), bias.data(), y.data());
      conv_fwd_bf16_reference(s, xb.data(), w.data(), bias.data(), ref.data());
      CHECK(padding_is_zero(y, c.n, c.oc, s.oh(), s.ow()));
      // |x w| summed over one output's taps bounds fp32 summation error.
      worst = std::max(worst, check_against_reference(y, ref, double(c.ic) * c.k * c.k, 2e-6, relu));
    }
  WARN("conv_bf16 on AMX worst error against the bf16 reference, relative to ic k k: " << worst);
}

TEST_CASE("conv_bf16 stays within bf16's rounding of the fp32 convolution", "[conv_bf16]") {
  yelan::test::amx_or_skip();
  // The rounding itself: each operand within 2^-9 relative, so each product within 2^-8,
  // and the sum within 2^-8 x sum |x w| of the fp32 convolution.
  const ConvShape s = shape_of({1, 48, 12, 14, 40, 3, 1}, false);
  const auto x = random_floats(std::size_t(48) * 12 * 14, 3);
  const auto w = random_floats(std::size_t(40) * 48 * 9, 4);
  const auto xb = to_blocked(x, 1, 48, 12, 14);
  std::vector<std::uint16_t> wp(conv_bf16_weight_halves(s));
  pack_conv_bf16_weights(s, w.data(), wp.data());
  const std::size_t ny = std::size_t(s.ocb()) * 12 * 14 * kBlock;
  std::vector<float> y(ny), ref(ny);
  conv_fwd_bf16_amx(s, xb.data(), wp.data(), nullptr, y.data());
  std::vector<float> wf(conv_weight_floats(s));
  pack_conv_weights(s, w.data(), ConvPack::fwd, wf.data());
  conv_scalar.fwd(s, xb.data(), wf.data(), nullptr, ref.data());
  check_rounded_fp32(y, ref, 48.0 * 9, std::ldexp(1.0, -8));
}

struct DeconvCase {
  int n, ic, ih, iw, oc;
};

// A bf16 up-sampling kernel (pack, then run) against deconv2x2_fwd_bf16_reference: both see
// the same rounded operands, so only the order of the fp32 sums differs.
template <class Halves, class Pack, class Run>
void check_deconv2x2_bf16(const std::vector<DeconvCase>& cases, Halves halves, Pack pack, Run run) {
  DeconvShape d;
  d.kh = d.kw = 2;
  d.stride = 2;
  for (const DeconvCase& c : cases) {
    INFO("n " << c.n << " ic " << c.ic << " " << c.ih << "x" << c.iw << " oc " << c.oc);
    d.n = c.n; d.ic = c.ic; d.ih = c.ih; d.iw = c.iw; d.oc = c.oc;
    const auto x = random_floats(std::size_t(c.n) * c.ic * c.ih * c.iw, 3 + c.ic);
    const auto w = random_floats(std::size_t(c.ic) * c.oc * 4, 7 + c.oc);
    std::vector<float> bias((c.oc + 15) / 16 * 16, 0.f);
    const auto b = random_floats(std::size_t(c.oc), 2);
    std::copy(b.begin(), b.end(), bias.begin());
    const auto xb = to_blocked(x, c.n, c.ic, c.ih, c.iw);
    std::vector<std::uint16_t> wp(halves(d));
    pack(d, w.data(), wp.data());
    const std::size_t ny = std::size_t(c.n) * ((c.oc + 15) / 16) * d.oh() * d.ow() * kBlock;
    std::vector<float> y(ny, -7.f), ref(ny);
    run(d, xb.data(), wp.data(), bias.data(), y.data());
    deconv2x2_fwd_bf16_reference(d, xb.data(), w.data(), bias.data(), ref.data());
    CHECK(padding_is_zero(y, c.n, c.oc, d.oh(), d.ow()));
    for (std::size_t i = 0; i < ny; ++i) REQUIRE(std::fabs(double(y[i]) - ref[i]) <= 2e-6 * c.ic);
  }
}

TEST_CASE("the 2x2/2 transposed convolution in bf16 on AMX equals its bf16 reference", "[conv_bf16]") {
  yelan::test::amx_or_skip();
  // the U-Net's ups (384->192 at 8x10, 48->24 over many rows), odd channels, a 1x1 input, a batch of 2
  check_deconv2x2_bf16({{1, 384, 8, 10, 192}, {1, 48, 33, 43, 24}, {1, 40, 5, 7, 20}, {1, 16, 1, 1, 8}, {2, 24, 6, 9, 40}},
                       deconv2x2_bf16_weight_halves, pack_deconv2x2_bf16_weights, deconv2x2_fwd_bf16_amx);
}

TEST_CASE("the 2x2/2 transposed convolution in bf16 pairs on AVX512-BF16 equals its bf16 reference", "[conv_bf16]") {
  yelan::test::winograd_bf16_or_skip();
  // The U-Net's four ups (12 output blocks: three groups of four; 24 outputs: a full block and
  // a half), half blocks alone (8 and 72 outputs), an odd input count (a pair half padding), 40 outputs (a half block after full
  // ones), chunks of 96 pixels with a remainder, rows that cross chunks, a 1x1 input, a batch.
  check_deconv2x2_bf16({{1, 384, 8, 10, 192},
                        {1, 192, 16, 21, 96},
                        {1, 96, 32, 43, 48},
                        {1, 48, 65, 86, 24},
                        {1, 37, 11, 13, 40},
                        {1, 16, 1, 1, 8},
                        {2, 24, 6, 9, 40},
                        {1, 70, 7, 15, 72}},
                       deconv2x2_bf16_pairs_weight_halves, pack_deconv2x2_bf16_pairs_weights,
                       deconv2x2_fwd_bf16_pairs);
}

TEST_CASE("the bf16 pairs' up-sampling refuses other shapes, and CPUs without AVX512-BF16", "[conv_bf16]") {
  DeconvShape d;
  d.kh = d.kw = 2;
  d.stride = 2;
  d.ic = 16; d.ih = 4; d.iw = 4; d.oc = 16;
  std::vector<float> x(16 * 16), y(16 * 64);
  std::vector<std::uint16_t> w(deconv2x2_bf16_pairs_weight_halves(d));
  DeconvShape padded = d;
  padded.pad_h = padded.pad_w = 1;
  CHECK_THROWS_AS(deconv2x2_fwd_bf16_pairs(padded, x.data(), w.data(), nullptr, y.data()), std::invalid_argument);
  if (!winograd_bf16_available())
    CHECK_THROWS_AS(deconv2x2_fwd_bf16_pairs(d, x.data(), w.data(), nullptr, y.data()), std::logic_error);
  else
    CHECK_NOTHROW(deconv2x2_fwd_bf16_pairs(d, x.data(), w.data(), nullptr, y.data()));
}

TEST_CASE("Winograd in bf16 on AVX512-BF16 equals its bf16 reference on odd shapes, with bias and fused ReLU", "[conv_bf16][winograd]") {
  yelan::test::winograd_bf16_or_skip();
  // Stage 1's shapes (24 channels: a half last block; 384 on 8 x 10), odd channel counts
  // (a pair half padding), maps smaller than a tile, a batch, several chunks of 48 tiles.
  const Case cases[] = {
      {1, 24, 13, 17, 24, 3, 1}, {1, 16, 9, 21, 24, 3, 1}, {1, 48, 8, 10, 48, 3, 1},  {2, 40, 7, 5, 40, 3, 1},
      {1, 17, 11, 12, 33, 3, 1}, {1, 3, 2, 3, 5, 3, 1},    {1, 96, 16, 21, 96, 3, 1}, {1, 64, 33, 43, 72, 3, 0},
      {1, 9, 30, 31, 8, 3, 1},   {1, 384, 8, 10, 192, 3, 1}, {1, 6, 19, 23, 24, 3, 1},
  };
  double worst = 0;
  for (const Case& c : cases)
    for (bool relu : {false, true}) {
      const ConvShape s = shape_of(c, relu);
      REQUIRE(winograd_applicable(s));
      INFO("n " << c.n << " ic " << c.ic << " " << c.ih << "x" << c.iw << " oc " << c.oc << " pad " << c.pad
                << " relu " << relu);
      const auto x = random_floats(std::size_t(c.n) * c.ic * c.ih * c.iw, 31 + c.ic);
      const auto w = random_floats(std::size_t(c.oc) * c.ic * 9, 37 + c.oc);
      std::vector<float> bias(std::size_t(s.ocb()) * kBlock, 0.f);
      const auto b = random_floats(std::size_t(c.oc), 7);
      std::copy(b.begin(), b.end(), bias.begin());
      const auto xb = to_blocked(x, c.n, c.ic, c.ih, c.iw);
      std::vector<float> u(winograd_weight_floats(s));
      pack_winograd_weights(s, w.data(), u.data());
      std::vector<std::uint16_t> ub(winograd_bf16_weight_halves(s));
      pack_winograd_bf16_weights(s, u.data(), ub.data());
      const std::size_t ny = std::size_t(c.n) * s.ocb() * s.oh() * s.ow() * kBlock;
      std::vector<float> y(ny, -7.f), ref(ny);
      conv_fwd_winograd_bf16(s, xb.data(), ub.data(), bias.data(), y.data());
      conv_fwd_winograd_bf16_reference(s, xb.data(), w.data(), bias.data(), ref.data());
      CHECK(padding_is_zero(y, c.n, c.oc, s.oh(), s.ow()));
      // The kernel's fp32 transforms sum in another order than the reference's, so a
      // transformed input can round to the neighbouring bf16: a few products off by 2^-8 of
      // themselves (measured worst 1.8e-6).
      worst = std::max(worst, check_against_reference(y, ref, double(c.ic) * 9, 2e-5, relu));
    }
  WARN("Winograd bf16 worst error against its reference, relative to ic k k: " << worst);
}

TEST_CASE("Winograd in bf16 stays within bf16's rounding of the fp32 convolution, and is not fp32", "[conv_bf16][winograd]") {
  yelan::test::winograd_bf16_or_skip();
  // Each transformed operand within 2^-9 relative; F(4,3)'s output transform sums 36
  // products with coefficients up to 8 x 8 and its weight transform scales by up to 1/4, so the
  // bound is looser than the direct kernel's 2^-8 (measured below; README says it).
  const ConvShape s = shape_of({1, 48, 12, 14, 40, 3, 1}, false);
  const auto x = random_floats(std::size_t(48) * 12 * 14, 3);
  const auto w = random_floats(std::size_t(40) * 48 * 9, 4);
  const auto xb = to_blocked(x, 1, 48, 12, 14);
  std::vector<float> u(winograd_weight_floats(s));
  pack_winograd_weights(s, w.data(), u.data());
  std::vector<std::uint16_t> ub(winograd_bf16_weight_halves(s));
  pack_winograd_bf16_weights(s, u.data(), ub.data());
  const std::size_t ny = std::size_t(s.ocb()) * 12 * 14 * kBlock;
  std::vector<float> y(ny), ref(ny);
  conv_fwd_winograd_bf16(s, xb.data(), ub.data(), nullptr, y.data());
  std::vector<float> wf(conv_weight_floats(s));
  pack_conv_weights(s, w.data(), ConvPack::fwd, wf.data());
  conv_scalar.fwd(s, xb.data(), wf.data(), nullptr, ref.data());
  const double worst = check_rounded_fp32(y, ref, 48.0 * 9, std::ldexp(1.0, -7));
  WARN("Winograd bf16 worst error against the fp32 convolution, relative to ic k k: " << worst);
}

TEST_CASE("Winograd in bf16 is taken where fp32 Winograd pays, and for few channels into 16 or more on 24 tiles", "[conv_bf16][winograd]") {
  CHECK(winograd_bf16_pays(shape_of({1, 6, 130, 173, 24, 3, 1}, false)));  // stage 1's first
  CHECK(winograd_bf16_pays(shape_of({1, 6, 24, 16, 16, 3, 1}, false)));    // 6 x 4 tiles
  CHECK_FALSE(winograd_bf16_pays(shape_of({1, 6, 20, 16, 16, 3, 1}, false)));  // 5 x 4
  CHECK_FALSE(winograd_bf16_pays(shape_of({1, 6, 24, 16, 15, 3, 1}, false)));  // 15 outputs
  CHECK(winograd_bf16_pays(shape_of({1, 64, 8, 8, 64, 3, 1}, false)));     // winograd_pays: wide
  CHECK_FALSE(winograd_bf16_pays(shape_of({1, 32, 8, 8, 32, 3, 1}, false)));  // neither
  ConvShape strided = shape_of({1, 6, 48, 48, 24, 3, 1}, false);
  strided.stride = 2;
  CHECK_FALSE(winograd_bf16_pays(strided));
}

TEST_CASE("Winograd in bf16 refuses shapes it does not compute, and CPUs without AVX512-BF16", "[conv_bf16][winograd]") {
  ConvShape s = shape_of({1, 16, 8, 8, 16, 3, 1}, false);
  s.stride = 2;
  std::vector<float> x(16 * 64), y(16 * 64);
  std::vector<std::uint16_t> u(winograd_bf16_weight_halves(shape_of({1, 16, 8, 8, 16, 3, 1}, false)));
  CHECK_THROWS_AS(conv_fwd_winograd_bf16(s, x.data(), u.data(), nullptr, y.data()), std::invalid_argument);
  const ConvShape ok = shape_of({1, 16, 8, 8, 16, 3, 1}, false);
  if (!winograd_bf16_available())
    CHECK_THROWS_AS(conv_fwd_winograd_bf16(ok, x.data(), u.data(), nullptr, y.data()), std::logic_error);
  else
    CHECK_NOTHROW(conv_fwd_winograd_bf16(ok, x.data(), u.data(), nullptr, y.data()));
}
