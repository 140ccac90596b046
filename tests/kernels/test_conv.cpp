#include <catch2/catch.hpp>

#include <omp.h>

#include <algorithm>
#include <cmath>

#include "conv_reference.h"
#include "kernels/conv.h"
#include "test_util.h"

using namespace yelan::kernels;
using yelan::test::conv_reference;
using yelan::test::from_blocked;
using yelan::test::padding_is_zero;
using yelan::test::random_floats;
using yelan::test::to_blocked;

namespace {

struct Case {
  int n, ic, ih, iw, oc, k, stride, pad;
};

ConvShape shape_of(const Case& c) {
  ConvShape s;
  s.n = c.n; s.ic = c.ic; s.ih = c.ih; s.iw = c.iw; s.oc = c.oc;
  s.kh = s.kw = c.k; s.stride = c.stride; s.pad_h = s.pad_w = c.pad;
  return s;
}

// Every kernel/stride/padding the networks use, on odd channel counts and sizes.
const Case kCases[] = {
    {1, 1, 1, 1, 1, 1, 1, 0},     {1, 3, 7, 5, 13, 3, 1, 1},    {2, 17, 7, 5, 3, 3, 2, 1},
    {1, 13, 33, 44, 17, 3, 1, 1}, {1, 17, 33, 44, 13, 3, 2, 1}, {1, 6, 33, 44, 64, 7, 2, 3},
    {1, 1, 17, 23, 17, 7, 2, 3},  {1, 64, 7, 5, 64, 1, 1, 0},   {1, 33, 9, 7, 31, 1, 2, 0},
    {1, 64, 33, 44, 64, 3, 1, 1}, {1, 3, 1, 1, 5, 3, 1, 1},     {1, 5, 3, 3, 7, 3, 2, 1},
    {2, 20, 12, 11, 40, 3, 2, 1}, {1, 64, 65, 87, 64, 3, 1, 1},
    // at most 8 channels in the last output block (the half tiles): the pose net's hourglass
    // layers (8 of 16), a tail of 19 columns, 24 (8 in the second block), a one-block 1x1
    {1, 8, 17, 22, 8, 3, 1, 1},   {2, 5, 6, 19, 8, 3, 1, 1},    {1, 16, 9, 11, 24, 3, 2, 1},
    {1, 9, 5, 13, 4, 1, 1, 0},
    // a half block after full ones in one tile (40: 2.5 blocks), and alone after a full
    // group of four (72: 4.5 blocks); the same as input channels (backward-data's output)
    {1, 10, 9, 21, 40, 3, 1, 1},  {1, 7, 6, 26, 72, 3, 1, 1},   {1, 24, 11, 15, 20, 3, 1, 1},
    {2, 40, 7, 9, 12, 3, 2, 1},   {1, 72, 5, 8, 3, 3, 1, 1},
};

struct Run {
  std::vector<float> y, dx, dw, db;
};

Run run_kernels(const ConvKernels& k, const ConvShape& s, const std::vector<float>& x,
                const std::vector<float>& w, const std::vector<float>& b, const std::vector<float>& dy) {
  std::vector<float> wf(conv_weight_floats(s)), wb(conv_weight_floats(s));
  pack_conv_weights(s, w.data(), ConvPack::fwd, wf.data());
  pack_conv_weights(s, w.data(), ConvPack::bwd_data, wb.data());
  std::vector<float> bias(std::size_t(s.ocb()) * kBlock, 0.f);
  std::copy(b.begin(), b.end(), bias.begin());
  const auto xb = to_blocked(x, s.n, s.ic, s.ih, s.iw);
  const auto dyb = to_blocked(dy, s.n, s.oc, s.oh(), s.ow());
  std::vector<float> yb(dyb.size(), -7.f), dxb(xb.size(), -7.f), dwp(wf.size(), -7.f), db(bias.size(), -7.f);
  k.fwd(s, xb.data(), wf.data(), bias.data(), yb.data());
  k.bwd_data(s, dyb.data(), wb.data(), nullptr, dxb.data());
  k.bwd_weights(s, xb.data(), dyb.data(), dwp.data(), db.data());
  REQUIRE(padding_is_zero(yb, s.n, s.oc, s.oh(), s.ow()));
  REQUIRE(padding_is_zero(dxb, s.n, s.ic, s.ih, s.iw));
  Run r;
  r.y = from_blocked(yb, s.n, s.oc, s.oh(), s.ow());
  r.dx = from_blocked(dxb, s.n, s.ic, s.ih, s.iw);
  r.dw.resize(w.size());
  unpack_conv_weights(s, dwp.data(), r.dw.data());
  r.db.assign(db.begin(), db.begin() + s.oc);
  for (int o = s.oc; o < s.ocb() * kBlock; ++o) REQUIRE(db[o] == 0.f);
  return r;
}

// |got - want| <= tol * scale, where scale bounds the magnitude of the summed terms.
void check_close(const char* what, const std::vector<float>& got, const std::vector<double>& want,
                 const std::vector<double>& scale, double tol) {
  REQUIRE(got.size() == want.size());
  double worst = 0;
  std::size_t worst_i = 0;
  for (std::size_t i = 0; i < got.size(); ++i) {
    const double err = std::abs(got[i] - want[i]) / (scale[i] + 1e-30);
    if (err > worst) { worst = err; worst_i = i; }
  }
  INFO(what << ": worst relative error " << worst << " at " << worst_i << " (got " << got[worst_i]
            << ", want " << want[worst_i] << ")");
  CHECK(worst <= tol);
}

// Magnitude scales for the backward results: the same sums with |terms|.
std::vector<double> abs_scale(const std::vector<double>& v, double floor_value) {
  std::vector<double> s(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) s[i] = std::abs(v[i]) + floor_value;
  return s;
}

}  // namespace

TEST_CASE("conv forward and backward match a double-precision reference on every ISA", "[kernels][conv]") {
  for (const Case& c : kCases) {
    const ConvShape s = shape_of(c);
    REQUIRE(s.valid());
    const auto x = random_floats(std::size_t(s.n) * s.ic * s.ih * s.iw, 11);
    const auto w = random_floats(std::size_t(s.oc) * s.ic * s.kh * s.kw, 12);
    const auto b = random_floats(s.oc, 13);
    const auto dy = random_floats(std::size_t(s.n) * s.oc * s.oh() * s.ow(), 14);
    const auto ref = conv_reference(s, x, w, b, dy);
    // Backward scales: the size of a typical term times the number of terms summed.
    const double terms_dx = double(s.oc) * s.kh * s.kw / (s.stride * s.stride) + 1;
    const double terms_dw = double(s.n) * s.oh() * s.ow() + 1;
    const auto dx_scale = abs_scale(ref.dx, 0.25 * std::sqrt(terms_dx));
    const auto dw_scale = abs_scale(ref.dw, 0.25 * std::sqrt(terms_dw));
    const auto db_scale = abs_scale(ref.db, 0.5 * std::sqrt(terms_dw));
    for (Isa isa : yelan::test::supported_isas()) {
      INFO("isa " << isa_name(isa) << " shape n" << c.n << " ic" << c.ic << " " << c.ih << "x" << c.iw
                  << " oc" << c.oc << " k" << c.k << " s" << c.stride << " p" << c.pad);
      const Run r = run_kernels(conv_kernels(isa), s, x, w, b, dy);
      check_close("y", r.y, ref.y, ref.y_abs, 1e-5);
      check_close("dx", r.dx, ref.dx, dx_scale, 1e-5);
      check_close("dw", r.dw, ref.dw, dw_scale, 1e-5);
      check_close("db", r.db, ref.db, db_scale, 1e-5);
    }
  }
}

TEST_CASE("conv backward passes are the adjoints of forward (finite differences, double)", "[kernels][conv]") {
  // L(x, w) = <dy, conv(x, w)>: dL/dx = bwd_data(dy), dL/dw = bwd_weights(x, dy). L is
  // linear in each, so a central difference in double is exact up to rounding.
  for (const Case& c : {Case{1, 3, 7, 5, 5, 3, 2, 1}, Case{1, 17, 6, 7, 3, 7, 2, 3}, Case{2, 4, 5, 5, 6, 1, 2, 0}}) {
    const ConvShape s = shape_of(c);
    const auto x = random_floats(std::size_t(s.n) * s.ic * s.ih * s.iw, 21);
    const auto w = random_floats(std::size_t(s.oc) * s.ic * s.kh * s.kw, 22);
    const auto dy = random_floats(std::size_t(s.n) * s.oc * s.oh() * s.ow(), 23);
    auto loss = [&](const std::vector<float>& xx, const std::vector<float>& ww, std::size_t xi, double dxv,
                    std::size_t wi, double dwv) {
      // <dy, conv> in double with one perturbed input or weight.
      double L = 0;
      for (int n = 0; n < s.n; ++n)
        for (int o = 0; o < s.oc; ++o)
          for (int oh = 0; oh < s.oh(); ++oh)
            for (int ow = 0; ow < s.ow(); ++ow) {
              double acc = 0;
              for (int i = 0; i < s.ic; ++i)
                for (int kh = 0; kh < s.kh; ++kh)
                  for (int kw = 0; kw < s.kw; ++kw) {
                    const int ih = oh * s.stride - s.pad_h + kh, iw = ow * s.stride - s.pad_w + kw;
                    if (ih < 0 || ih >= s.ih || iw < 0 || iw >= s.iw) continue;
                    const std::size_t a = ((std::size_t(n) * s.ic + i) * s.ih + ih) * s.iw + iw;
                    const std::size_t bi = ((std::size_t(o) * s.ic + i) * s.kh + kh) * s.kw + kw;
                    acc += (xx[a] + (a == xi ? dxv : 0.0)) * (ww[bi] + (bi == wi ? dwv : 0.0));
                  }
              L += acc * dy[((std::size_t(n) * s.oc + o) * s.oh() + oh) * s.ow() + ow];
            }
      return L;
    };
    const double h = 1e-3;
    for (Isa isa : yelan::test::supported_isas()) {
      const Run r = run_kernels(conv_kernels(isa), s, x, w, {}, dy);
      for (std::size_t xi = 0; xi < x.size(); xi += 7) {
        const double fd = (loss(x, w, xi, h, SIZE_MAX, 0) - loss(x, w, xi, -h, SIZE_MAX, 0)) / (2 * h);
        INFO("isa " << isa_name(isa) << " dx[" << xi << "]");
        REQUIRE(std::abs(r.dx[xi] - fd) <= 1e-4 * (1 + std::abs(fd)));
      }
      for (std::size_t wi = 0; wi < w.size(); wi += 5) {
        const double fd = (loss(x, w, SIZE_MAX, 0, wi, h) - loss(x, w, SIZE_MAX, 0, wi, -h)) / (2 * h);
        INFO("isa " << isa_name(isa) << " dw[" << wi << "]");
        REQUIRE(std::abs(r.dw[wi] - fd) <= 1e-4 * (1 + std::abs(fd)));
      }
    }
  }
}

TEST_CASE("conv ISA variants agree with each other up to rounding", "[kernels][conv]") {
  const ConvShape s = shape_of({1, 20, 13, 17, 36, 3, 1, 1});
  const auto x = random_floats(std::size_t(s.n) * s.ic * s.ih * s.iw, 31);
  const auto w = random_floats(std::size_t(s.oc) * s.ic * s.kh * s.kw, 32);
  const auto dy = random_floats(std::size_t(s.n) * s.oc * s.oh() * s.ow(), 33);
  const Run base = run_kernels(conv_scalar, s, x, w, {}, dy);
  for (Isa isa : yelan::test::supported_isas()) {
    const Run r = run_kernels(conv_kernels(isa), s, x, w, {}, dy);
    for (std::size_t i = 0; i < r.y.size(); ++i) REQUIRE(std::abs(r.y[i] - base.y[i]) <= 2e-5f * (1 + std::abs(base.y[i])));
    for (std::size_t i = 0; i < r.dx.size(); ++i) REQUIRE(std::abs(r.dx[i] - base.dx[i]) <= 2e-5f * (1 + std::abs(base.dx[i])));
    for (std::size_t i = 0; i < r.dw.size(); ++i) REQUIRE(std::abs(r.dw[i] - base.dw[i]) <= 1e-4f * (1 + std::abs(base.dw[i])));
  }
}

TEST_CASE("conv shapes outside the supported range are reported invalid", "[kernels][conv]") {
  CHECK_FALSE(shape_of({1, 3, 2, 2, 4, 7, 1, 0}).valid());   // kernel larger than the input
  CHECK_FALSE(shape_of({1, 3, 8, 8, 4, 3, 1, 3}).valid());   // pad >= kernel
  CHECK_FALSE(shape_of({0, 3, 8, 8, 4, 3, 1, 1}).valid());
  CHECK_FALSE(shape_of({1, 3, 20, 20, 4, 13, 1, 1}).valid());  // above kMaxKernel
  CHECK(shape_of({1, 3, 8, 8, 4, 3, 2, 1}).valid());
}

TEST_CASE("transposed conv (3x3/2 with output_padding, 2x2/2, 1x1/2) matches its definition", "[kernels][deconv]") {
  struct D { int n, ic, ih, iw, oc, k, stride, pad, oph, opw; };
  for (const D& d : {D{1, 64, 17, 22, 64, 3, 2, 1, 0, 1}, D{1, 3, 7, 5, 13, 3, 2, 1, 1, 1}, D{2, 17, 4, 3, 5, 2, 2, 0, 0, 0},
                     D{1, 13, 5, 7, 17, 1, 2, 0, 1, 1}, D{1, 128, 9, 11, 64, 3, 2, 1, 0, 0}}) {
    DeconvShape s;
    s.n = d.n; s.ic = d.ic; s.ih = d.ih; s.iw = d.iw; s.oc = d.oc; s.kh = s.kw = d.k; s.stride = d.stride;
    s.pad_h = s.pad_w = d.pad; s.out_pad_h = d.oph; s.out_pad_w = d.opw;
    REQUIRE(s.valid());
    const int OH = s.oh(), OW = s.ow();
    const auto x = random_floats(std::size_t(s.n) * s.ic * s.ih * s.iw, 41);
    const auto w = random_floats(std::size_t(s.ic) * s.oc * s.kh * s.kw, 42);  // (in, out, kh, kw)
    const auto b = random_floats(s.oc, 43);
    const auto dy = random_floats(std::size_t(s.n) * s.oc * OH * OW, 44);
    // The definition: every input pixel scatters w[i][o] into the output at ih*s - p + kh.
    std::vector<double> y(dy.size()), mag(dy.size()), dx(x.size()), dw(w.size()), db(s.oc);
    for (int n = 0; n < s.n; ++n)
      for (int o = 0; o < s.oc; ++o)
        for (int p = 0; p < OH * OW; ++p) {
          y[(std::size_t(n) * s.oc + o) * OH * OW + p] = b[o];
          mag[(std::size_t(n) * s.oc + o) * OH * OW + p] = std::abs(b[o]);
          db[o] += dy[(std::size_t(n) * s.oc + o) * OH * OW + p];
        }
    for (int n = 0; n < s.n; ++n)
      for (int i = 0; i < s.ic; ++i)
        for (int ih = 0; ih < s.ih; ++ih)
          for (int iw = 0; iw < s.iw; ++iw)
            for (int o = 0; o < s.oc; ++o)
              for (int kh = 0; kh < s.kh; ++kh)
                for (int kw = 0; kw < s.kw; ++kw) {
                  const int oh = ih * s.stride - s.pad_h + kh, ow = iw * s.stride - s.pad_w + kw;
                  if (oh < 0 || oh >= OH || ow < 0 || ow >= OW) continue;
                  const std::size_t xi = ((std::size_t(n) * s.ic + i) * s.ih + ih) * s.iw + iw;
                  const std::size_t wi = ((std::size_t(i) * s.oc + o) * s.kh + kh) * s.kw + kw;
                  const std::size_t yi = ((std::size_t(n) * s.oc + o) * OH + oh) * OW + ow;
                  y[yi] += double(x[xi]) * w[wi];
                  mag[yi] += std::abs(double(x[xi]) * w[wi]);
                  dx[xi] += double(dy[yi]) * w[wi];
                  dw[wi] += double(dy[yi]) * x[xi];
                }
    const ConvShape c = s.as_conv();
    std::vector<float> wf(conv_weight_floats(c)), wb(conv_weight_floats(c));
    pack_conv_weights(c, w.data(), ConvPack::fwd, wf.data());
    pack_conv_weights(c, w.data(), ConvPack::bwd_data, wb.data());
    std::vector<float> bias(std::size_t(c.icb()) * kBlock, 0.f);
    std::copy(b.begin(), b.end(), bias.begin());
    const auto xb = to_blocked(x, s.n, s.ic, s.ih, s.iw);
    const auto dyb = to_blocked(dy, s.n, s.oc, OH, OW);
    for (Isa isa : yelan::test::supported_isas()) {
      INFO("isa " << isa_name(isa) << " deconv " << d.ic << "->" << d.oc << " " << d.ih << "x" << d.iw << " k" << d.k);
      const ConvKernels& k = conv_kernels(isa);
      std::vector<float> yb(dyb.size()), dxb(xb.size()), dwp(wf.size()), dbb(bias.size());
      deconv_fwd(k, s, xb.data(), wb.data(), bias.data(), yb.data());
      deconv_bwd_data(k, s, dyb.data(), wf.data(), dxb.data());
      deconv_bwd_weights(k, s, xb.data(), dyb.data(), dwp.data(), dbb.data());
      REQUIRE(padding_is_zero(yb, s.n, s.oc, OH, OW));
      std::vector<float> dwo(w.size());
      unpack_conv_weights(c, dwp.data(), dwo.data());
      check_close("y", from_blocked(yb, s.n, s.oc, OH, OW), y, mag, 1e-5);
      check_close("dx", from_blocked(dxb, s.n, s.ic, s.ih, s.iw), dx, abs_scale(dx, 0.25 * std::sqrt(double(s.oc) * s.kh * s.kw)), 1e-5);
      check_close("dw", dwo, dw, abs_scale(dw, 0.25 * std::sqrt(double(s.n) * s.ih * s.iw)), 1e-5);
      check_close("db", std::vector<float>(dbb.begin(), dbb.begin() + s.oc), db, abs_scale(db, 0.5 * std::sqrt(double(OH) * OW * s.n)), 1e-5);
    }
  }
}

TEST_CASE("Winograd F(4,3) inference path stays within its documented error", "[kernels][winograd]") {
  // Error measure: |y - y_ref| / sum |x w| per output (the direct path is within 1e-5).
  // F(4,3)'s transforms amplify rounding by their coefficients (up to 8 and 1/24); the
  // bound below is what this test measures with margin, and README states it.
  const double kBound = 2e-5;  // measured worst: 2.5e-6 on these shapes
  double worst_seen = 0;
  for (const Case& c : {Case{1, 1, 1, 1, 1, 3, 1, 1}, Case{1, 3, 7, 5, 13, 3, 1, 1}, Case{2, 17, 7, 5, 3, 3, 1, 1},
                        Case{1, 13, 33, 44, 17, 3, 1, 1}, Case{1, 5, 9, 9, 7, 3, 1, 0}, Case{1, 64, 65, 87, 64, 3, 1, 1},
                        Case{1, 128, 33, 44, 128, 3, 1, 1},
                        // half last blocks: beside full ones (24, 40), alone after a group (72)
                        Case{1, 24, 13, 19, 24, 3, 1, 1}, Case{1, 20, 9, 23, 40, 3, 1, 1},
                        Case{1, 9, 11, 14, 72, 3, 1, 1}}) {
    const ConvShape s = shape_of(c);
    REQUIRE(winograd_applicable(s));
    const auto x = random_floats(std::size_t(s.n) * s.ic * s.ih * s.iw, 51);
    const auto w = random_floats(std::size_t(s.oc) * s.ic * 9, 52);
    const auto b = random_floats(s.oc, 53);
    const auto ref = conv_reference(s, x, w, b, std::vector<float>(std::size_t(s.n) * s.oc * s.oh() * s.ow(), 0.f));
    std::vector<float> u(winograd_weight_floats(s));
    pack_winograd_weights(s, w.data(), u.data());
    std::vector<float> bias(std::size_t(s.ocb()) * kBlock, 0.f);
    std::copy(b.begin(), b.end(), bias.begin());
    const auto xb = to_blocked(x, s.n, s.ic, s.ih, s.iw);
    for (Isa isa : yelan::test::supported_isas()) {
      if (isa == Isa::scalar && s.ic * s.oc > 20000) continue;  // the textbook loop is slow
      INFO("isa " << isa_name(isa) << " ic" << c.ic << " oc" << c.oc << " " << c.ih << "x" << c.iw << " p" << c.pad);
      std::vector<float> yb(std::size_t(s.n) * s.ocb() * s.oh() * s.ow() * kBlock, -3.f);
      conv_kernels(isa).fwd_winograd(s, xb.data(), u.data(), bias.data(), yb.data());
      REQUIRE(padding_is_zero(yb, s.n, s.oc, s.oh(), s.ow()));
      const auto y = from_blocked(yb, s.n, s.oc, s.oh(), s.ow());
      double worst = 0;
      for (std::size_t i = 0; i < y.size(); ++i)
        worst = std::max(worst, std::abs(y[i] - ref.y[i]) / (ref.y_abs[i] + 1e-30));
      worst_seen = std::max(worst_seen, worst);
      CHECK(worst <= kBound);
    }
  }
  WARN("Winograd F(4,3) worst relative error (vs sum |x w|): " << worst_seen);
}

TEST_CASE("Winograd runs where it pays inside a network: wide or large maps, never 8-channel blocks", "[kernels][winograd]") {
  // stage 2's hourglass (8 and 16 channels on 17x22 and 9x11 maps) and stage 1's U-Net
  REQUIRE_FALSE(winograd_pays(shape_of({1, 8, 17, 22, 8, 3, 1, 1})));
  REQUIRE_FALSE(winograd_pays(shape_of({1, 8, 33, 44, 8, 3, 1, 1})));
  REQUIRE_FALSE(winograd_pays(shape_of({1, 16, 9, 11, 16, 3, 1, 1})));    // 9 tiles
  REQUIRE_FALSE(winograd_pays(shape_of({1, 16, 17, 22, 8, 3, 1, 1})));
  REQUIRE(winograd_pays(shape_of({1, 16, 17, 22, 16, 3, 1, 1})));         // 30 tiles
  REQUIRE(winograd_pays(shape_of({3, 16, 9, 11, 16, 3, 1, 1})));          // a batch of 3: 27
  REQUIRE(winograd_pays(shape_of({1, 24, 130, 173, 24, 3, 1, 1})));
  REQUIRE(winograd_pays(shape_of({1, 384, 8, 10, 384, 3, 1, 1})));        // 6 tiles, but wide
  REQUIRE_FALSE(winograd_pays(shape_of({1, 64, 33, 44, 64, 3, 2, 1})));   // stride 2: not applicable
  REQUIRE_FALSE(winograd_pays(shape_of({1, 64, 33, 44, 64, 1, 1, 0})));
}

TEST_CASE("a fused ReLU stores exactly max(0, y) of the same forward, direct and Winograd, on every ISA", "[kernels][conv][winograd]") {
  for (const Case& c : kCases) {
    ConvShape s = shape_of(c);
    const auto x = random_floats(std::size_t(s.n) * s.ic * s.ih * s.iw, 61);
    const auto w = random_floats(std::size_t(s.oc) * s.ic * s.kh * s.kw, 62);
    const auto b = random_floats(s.oc, 63);
    std::vector<float> wf(conv_weight_floats(s));
    pack_conv_weights(s, w.data(), ConvPack::fwd, wf.data());
    std::vector<float> u;
    if (winograd_applicable(s)) {
      u.resize(winograd_weight_floats(s));
      pack_winograd_weights(s, w.data(), u.data());
    }
    std::vector<float> bias(std::size_t(s.ocb()) * kBlock, 0.f);
    std::copy(b.begin(), b.end(), bias.begin());
    const auto xb = to_blocked(x, s.n, s.ic, s.ih, s.iw);
    const std::size_t ny = std::size_t(s.n) * s.ocb() * s.oh() * s.ow() * kBlock;
    for (Isa isa : yelan::test::supported_isas()) {
      const ConvKernels& k = conv_kernels(isa);
      for (const bool wino : {false, true}) {
        if (wino && u.empty()) continue;
        if (wino && isa == Isa::scalar && s.ic * s.oc > 20000) continue;  // the textbook loop is slow
        INFO("isa " << isa_name(isa) << (wino ? " winograd" : " direct") << " n" << c.n << " ic" << c.ic << " " << c.ih
                    << "x" << c.iw << " oc" << c.oc << " k" << c.k << " s" << c.stride << " p" << c.pad);
        std::vector<float> plain(ny, -5.f), fused(ny, -5.f);
        s.relu = false;
        (wino ? k.fwd_winograd : k.fwd)(s, xb.data(), wino ? u.data() : wf.data(), bias.data(), plain.data());
        s.relu = true;
        (wino ? k.fwd_winograd : k.fwd)(s, xb.data(), wino ? u.data() : wf.data(), bias.data(), fused.data());
        REQUIRE(padding_is_zero(fused, s.n, s.oc, s.oh(), s.ow()));
        std::size_t negative = 0, differ = 0;
        for (std::size_t i = 0; i < ny; ++i) {
          negative += plain[i] < 0.f;
          differ += fused[i] != (plain[i] > 0.f ? plain[i] : 0.f);
        }
        CHECK(differ == 0);
        CHECK(negative > 0);  // the ReLU had something to clip
      }
    }
  }
}

// The tile unrolls a source block of exactly 8 channels (8-channel maps, 24-channel ones' last
// block) as it does a full one, and so does AVX2's half_row3 (the cases with 8 output
// channels, 3x3 stride 1, go through it); any other count takes the counted loop. The same
// convolution with a ninth channel that is zero in x and w takes that loop and must give the
// same bits: each lane into the same partial sum, in the same order (x * 0 adds +0).
TEST_CASE("an 8-channel source block gives the bits of the counted loop (a ninth, zero channel), direct and Winograd", "[kernels][conv][winograd]") {
  for (const Case& c : {Case{1, 8, 17, 22, 8, 3, 1, 1}, Case{2, 8, 9, 13, 16, 3, 1, 1}, Case{1, 8, 9, 11, 12, 3, 2, 1},
                        Case{1, 24, 13, 19, 24, 3, 1, 1}, Case{1, 40, 7, 26, 20, 3, 1, 1}, Case{1, 8, 7, 9, 40, 1, 1, 0}}) {
    ConvShape s = shape_of(c), s9 = s;
    s9.ic = s.ic + 1;
    const int K = s.kh * s.kw;
    const auto x = random_floats(std::size_t(s.n) * s.ic * s.ih * s.iw, 71);
    const auto w = random_floats(std::size_t(s.oc) * s.ic * K, 72);
    const auto b = random_floats(s.oc, 73);
    std::vector<float> x9(std::size_t(s.n) * s9.ic * s.ih * s.iw, 0.f), w9(std::size_t(s.oc) * s9.ic * K, 0.f);
    const std::size_t plane = std::size_t(s.ih) * s.iw;
    for (int n = 0; n < s.n; ++n)
      std::copy_n(x.begin() + std::ptrdiff_t(n) * s.ic * plane, s.ic * plane, x9.begin() + std::ptrdiff_t(n) * s9.ic * plane);
    for (int o = 0; o < s.oc; ++o)
      std::copy_n(w.begin() + std::ptrdiff_t(o) * s.ic * K, s.ic * K, w9.begin() + std::ptrdiff_t(o) * s9.ic * K);
    std::vector<float> bias(std::size_t(s.ocb()) * kBlock, 0.f);
    std::copy(b.begin(), b.end(), bias.begin());
    const auto xb = to_blocked(x, s.n, s.ic, s.ih, s.iw), xb9 = to_blocked(x9, s.n, s9.ic, s.ih, s.iw);
    const bool wino = winograd_applicable(s);
    std::vector<float> wf(conv_weight_floats(s)), wf9(conv_weight_floats(s9)), u, u9;
    pack_conv_weights(s, w.data(), ConvPack::fwd, wf.data());
    pack_conv_weights(s9, w9.data(), ConvPack::fwd, wf9.data());
    if (wino) {
      u.resize(winograd_weight_floats(s));
      u9.resize(winograd_weight_floats(s9));
      pack_winograd_weights(s, w.data(), u.data());
      pack_winograd_weights(s9, w9.data(), u9.data());
    }
    const std::size_t ny = std::size_t(s.n) * s.ocb() * s.oh() * s.ow() * kBlock;
    for (Isa isa : yelan::test::supported_isas()) {
      if (isa == Isa::scalar) continue;  // plain loops: no tiles
      const ConvKernels& k = conv_kernels(isa);
      for (const bool relu : {false, true}) {
        s.relu = s9.relu = relu;
        INFO("isa " << isa_name(isa) << " n" << c.n << " ic" << c.ic << " " << c.ih << "x" << c.iw << " oc" << c.oc
                    << " k" << c.k << " s" << c.stride << (relu ? " relu" : ""));
        std::vector<float> y(ny, -5.f), y9(ny, 5.f);
        k.fwd(s, xb.data(), wf.data(), bias.data(), y.data());
        k.fwd(s9, xb9.data(), wf9.data(), bias.data(), y9.data());
        CHECK(y == y9);
        if (!wino) continue;
        std::fill(y.begin(), y.end(), -5.f);
        std::fill(y9.begin(), y9.end(), 5.f);
        k.fwd_winograd(s, xb.data(), u.data(), bias.data(), y.data());
        k.fwd_winograd(s9, xb9.data(), u9.data(), bias.data(), y9.data());
        CHECK(y == y9);
      }
    }
  }
}

TEST_CASE("conv kernels give the same bits on one thread, on two, and called from each thread of a parallel region", "[kernels][conv][threads]") {
  // kernels/parallel.h: on one thread the loops run without a parallel region; inside an
  // enclosing region they must still open their own (a loop left orphaned there would be
  // shared among the caller's team, and each caller would fill only its share of the output).
  const int saved = omp_get_max_threads();
  // Small shapes run on the caller alone (worth_sharing); the large ones are shared.
  for (const Case& c : {Case{1, 8, 17, 22, 8, 3, 1, 1}, Case{2, 17, 33, 44, 13, 3, 2, 1}, Case{1, 40, 40, 50, 40, 3, 1, 1},
                        Case{2, 24, 45, 61, 20, 3, 2, 1}}) {
    const ConvShape s = shape_of(c);
    const auto x = random_floats(std::size_t(s.n) * s.ic * s.ih * s.iw, 71);
    const auto w = random_floats(std::size_t(s.oc) * s.ic * s.kh * s.kw, 72);
    const auto dy = random_floats(std::size_t(s.n) * s.oc * s.oh() * s.ow(), 73);
    for (Isa isa : yelan::test::supported_isas()) {
      const ConvKernels& k = conv_kernels(isa);
      INFO("isa " << isa_name(isa) << " ic" << c.ic << " " << c.ih << "x" << c.iw << " oc" << c.oc << " s" << c.stride);
      omp_set_num_threads(1);
      const Run one = run_kernels(k, s, x, w, {}, dy);
      omp_set_num_threads(2);
      const Run two = run_kernels(k, s, x, w, {}, dy);
      CHECK(two.y == one.y);
      CHECK(two.dx == one.dx);
      CHECK(two.dw == one.dw);
      Run each[2];
#pragma omp parallel num_threads(2)
      each[omp_get_thread_num()] = run_kernels(k, s, x, w, {}, dy);
      for (const Run& r : each) {
        CHECK(r.y == one.y);
        CHECK(r.dx == one.dx);
        CHECK(r.dw == one.dw);
      }
      if (winograd_applicable(s)) {
        std::vector<float> u(winograd_weight_floats(s));
        pack_winograd_weights(s, w.data(), u.data());
        const auto xb = to_blocked(x, s.n, s.ic, s.ih, s.iw);
        const std::size_t ny = std::size_t(s.n) * s.ocb() * s.oh() * s.ow() * kBlock;
        std::vector<float> y1(ny, -3.f), y2[2] = {std::vector<float>(ny, -3.f), std::vector<float>(ny, -3.f)};
        omp_set_num_threads(1);
        k.fwd_winograd(s, xb.data(), u.data(), nullptr, y1.data());
#pragma omp parallel num_threads(2)
        k.fwd_winograd(s, xb.data(), u.data(), nullptr, y2[omp_get_thread_num()].data());
        CHECK(y2[0] == y1);
        CHECK(y2[1] == y1);
      }
    }
  }
  omp_set_num_threads(saved);
}
