#include <catch2/catch.hpp>

#include <cstring>
#include <stdexcept>
#include <vector>

#include "conv_reference.h"
#include "kernels/conv.h"
#include "kernels/conv_bf16.h"
#include "test_util.h"

using namespace yelan::kernels;
using yelan::test::random_floats;
using yelan::test::to_blocked;

namespace {

// The U-Net's up path: a_c skip channels at the convolution's size, b_c up-sampled ones of
// b_h x b_w placed at (top, left), then oc outputs.
struct CatCase {
  int a_c, b_c, h, w, b_h, b_w, top, left, oc;
  bool relu;
};

ConvShape shape_of(const CatCase& c) {
  ConvShape s;
  s.n = 1; s.ic = c.a_c + c.b_c; s.ih = c.h; s.iw = c.w; s.oc = c.oc;
  s.kh = s.kw = 3; s.stride = 1; s.pad_h = s.pad_w = 1; s.relu = c.relu;
  return s;
}

// Stage 1's joins (24 + 24: on 16 lanes a block of each map's channels meets inside one
// vector), b smaller than a and shifted (F.pad of an odd size), b_c not a multiple of 8
// (a half vector of b's padding joined), whole blocks (16 + 16, 32 + 8), 8 + 40.
const CatCase kCatCases[] = {
    {24, 24, 17, 22, 17, 22, 0, 0, 24, false}, {24, 24, 13, 11, 12, 10, 1, 0, 24, true},
    {24, 24, 9, 14, 8, 13, 0, 1, 16, false},  {16, 16, 10, 9, 10, 9, 0, 0, 20, true},
    {32, 8, 7, 12, 6, 12, 1, 0, 40, false},   {8, 40, 11, 6, 11, 5, 0, 1, 8, false},
    {24, 5, 9, 9, 8, 8, 1, 1, 24, true},      {48, 48, 8, 10, 8, 10, 0, 0, 24, false},
    {40, 24, 6, 7, 5, 6, 1, 1, 13, false},    {8, 24, 7, 9, 7, 9, 0, 0, 16, true},
};

struct CatInputs {
  std::vector<float> a, b;
  ConcatInput in;
};

CatInputs make_inputs(const CatCase& c, unsigned seed) {
  CatInputs r;
  r.a = to_blocked(random_floats(std::size_t(c.a_c) * c.h * c.w, seed), 1, c.a_c, c.h, c.w);
  r.b = to_blocked(random_floats(std::size_t(c.b_c) * c.b_h * c.b_w, seed + 1), 1, c.b_c, c.b_h, c.b_w);
  r.in.a = r.a.data(); r.in.a_c = c.a_c;
  r.in.b = r.b.data(); r.in.b_c = c.b_c; r.in.b_h = c.b_h; r.in.b_w = c.b_w;
  r.in.top = c.top; r.in.left = c.left;
  return r;
}

std::vector<float> bias_of(const ConvShape& s) {
  std::vector<float> bias(std::size_t(s.ocb()) * kBlock, 0.f);
  const auto b = random_floats(std::size_t(s.oc), 5);
  std::copy(b.begin(), b.end(), bias.begin());
  return bias;
}

std::size_t x_floats(const ConvShape& s) { return std::size_t(s.icb()) * s.ih * s.iw * kBlock; }

bool same_bits(const std::vector<float>& x, const std::vector<float>& y) {
  return x.size() == y.size() && std::memcmp(x.data(), y.data(), x.size() * sizeof(float)) == 0;
}

// What every in-place path refuses: a's channels not a multiple of 8, channels that do not add
// up, b past the input or missing, two images, a stride. `in` is taken by `applicable` for s.
void check_refusals(bool (*applicable)(const ConvShape&, const ConcatInput&), const ConvShape& s,
                    const ConcatInput& in) {
  REQUIRE(applicable(s, in));
  auto refused = [&](auto edit) {
    ConvShape s2 = s;
    ConcatInput in2 = in;
    edit(s2, in2);
    return !applicable(s2, in2);
  };
  CHECK(refused([](ConvShape&, ConcatInput& c) { c.a_c -= 4; c.b_c += 4; }));
  CHECK(refused([](ConvShape&, ConcatInput& c) { c.b_c -= 1; }));
  CHECK(refused([&](ConvShape&, ConcatInput& c) { c.top = s.ih - c.b_h + 1; }));
  CHECK(refused([](ConvShape&, ConcatInput& c) { c.left = -1; }));
  CHECK(refused([](ConvShape&, ConcatInput& c) { c.b = nullptr; }));
  CHECK(refused([](ConvShape& s2, ConcatInput&) { s2.n = 2; }));
  CHECK(refused([](ConvShape& s2, ConcatInput&) { s2.stride = 2; }));
}

}  // namespace

TEST_CASE("concat_input lays two maps side by side in channels, the second padded with zeros", "[kernels][winograd][concat]") {
  const CatCase c{8, 5, 4, 5, 3, 3, 1, 2, 8, false};
  const ConvShape s = shape_of(c);
  const CatInputs m = make_inputs(c, 3);
  std::vector<float> x(x_floats(s), -1.f);
  concat_input(s, m.in, x.data());
  const auto at = [&](const std::vector<float>& v, int ch, int h, int w, int hh, int ww) {
    return v[((std::size_t(ch / kBlock) * hh + h) * ww + w) * kBlock + ch % kBlock];
  };
  for (int ch = 0; ch < kBlock; ++ch)  // one block: 13 channels and 3 lanes of padding
    for (int h = 0; h < c.h; ++h)
      for (int w = 0; w < c.w; ++w) {
        INFO("channel " << ch << " at " << h << "," << w);
        const bool in_b = h >= c.top && h < c.top + c.b_h && w >= c.left && w < c.left + c.b_w;
        const float want = ch < c.a_c                       ? at(m.a, ch, h, w, c.h, c.w)
                           : ch < c.a_c + c.b_c && in_b ? at(m.b, ch - c.a_c, h - c.top, w - c.left, c.b_h, c.b_w)
                                                           : 0.f;
        REQUIRE(at(x, ch, h, w, c.h, c.w) == want);
      }
}

TEST_CASE("Winograd of two maps read in place equals Winograd of their copy, bit for bit, on every ISA", "[kernels][winograd][concat]") {
  for (const CatCase& c : kCatCases) {
    const ConvShape s = shape_of(c);
    INFO(c.a_c << " + " << c.b_c << " channels, " << c.h << "x" << c.w << ", b " << c.b_h << "x" << c.b_w << " at "
                << c.top << "," << c.left << ", oc " << c.oc << " relu " << c.relu);
    const CatInputs m = make_inputs(c, 11 + unsigned(c.b_c));
    REQUIRE(winograd_cat_applicable(s, m.in));
    std::vector<float> x(x_floats(s));
    concat_input(s, m.in, x.data());
    const auto w = random_floats(std::size_t(c.oc) * s.ic * 9, 17);
    std::vector<float> u(winograd_weight_floats(s));
    pack_winograd_weights(s, w.data(), u.data());
    const auto bias = bias_of(s);
    const std::size_t ny = std::size_t(s.ocb()) * s.oh() * s.ow() * kBlock;
    for (Isa isa : yelan::test::supported_isas()) {
      INFO("isa " << isa_name(isa));
      std::vector<float> copied(ny, -3.f), in_place(ny, -5.f);
      conv_kernels(isa).fwd_winograd(s, x.data(), u.data(), bias.data(), copied.data());
      conv_kernels(isa).fwd_winograd_cat(s, m.in, u.data(), bias.data(), in_place.data());
      CHECK(same_bits(copied, in_place));
    }
    if (winograd_bf16_available()) {
      std::vector<std::uint16_t> ub(winograd_bf16_weight_halves(s));
      pack_winograd_bf16_weights(s, u.data(), ub.data());
      std::vector<float> copied(ny, -3.f), in_place(ny, -5.f);
      conv_fwd_winograd_bf16(s, x.data(), ub.data(), bias.data(), copied.data());
      conv_fwd_winograd_bf16_cat(s, m.in, ub.data(), bias.data(), in_place.data());
      CHECK(same_bits(copied, in_place));
    }
  }
}

TEST_CASE("Winograd in place refuses inputs the two maps do not make", "[kernels][winograd][concat]") {
  const CatCase c{24, 24, 9, 10, 8, 9, 1, 1, 24, false};
  const CatInputs m = make_inputs(c, 7);
  const ConvShape s = shape_of(c);
  check_refusals(winograd_cat_applicable, s, m.in);
  auto refused = [&](auto edit) {
    ConvShape s2 = s;
    ConcatInput in2 = m.in;
    edit(s2, in2);
    return !winograd_cat_applicable(s2, in2);
  };
  // 24 + 5 is taken (the input's second block: a's channels 16-23, then b's 0-4); 40 + 27 is
  // not: an 8-lane vector of the input's last block (channels 72-79) would lie past b's two.
  CHECK_FALSE(refused([](ConvShape& s2, ConcatInput& in) { in.b_c = 5; s2.ic = 29; }));
  CHECK(refused([](ConvShape& s2, ConcatInput& in) { in.a_c = 40; in.b_c = 27; s2.ic = 67; }));
  std::vector<float> x(x_floats(s) * 2);
  ConcatInput bad = m.in;
  bad.top = 5;
  CHECK_THROWS_AS(concat_input(s, bad, x.data()), std::invalid_argument);
}

namespace {
// The concatenation built from the maps' plain (unblocked) values, as F.pad and torch.cat make it.
std::vector<float> copied_concat(const CatCase& c, unsigned seed) {
  const auto a = random_floats(std::size_t(c.a_c) * c.h * c.w, seed);
  const auto b = random_floats(std::size_t(c.b_c) * c.b_h * c.b_w, seed + 1);
  std::vector<float> x(std::size_t(c.a_c + c.b_c) * c.h * c.w, 0.f);
  std::copy(a.begin(), a.end(), x.begin());
  for (int ch = 0; ch < c.b_c; ++ch)
    for (int h = 0; h < c.b_h; ++h)
      for (int w = 0; w < c.b_w; ++w)
        x[((std::size_t(c.a_c + ch) * c.h + h + c.top) * c.w) + w + c.left] = b[(std::size_t(ch) * c.b_h + h) * c.b_w + w];
  return to_blocked(x, 1, c.a_c + c.b_c, c.h, c.w);
}
}  // namespace

// On AMX the tiles read a bf16 copy of the input that the kernel makes itself: made straight
// from the two maps, the result is the copied input's bit for bit. 40 + 27 (refused by
// Winograd: its last vector would read past b) is taken here: whole blocks of b are read.
TEST_CASE("AMX of two maps read in place equals AMX of their copy, bit for bit", "[kernels][conv_bf16][concat]") {
  yelan::test::amx_or_skip();
  std::vector<CatCase> cases(std::begin(kCatCases), std::end(kCatCases));
  cases.push_back({40, 27, 9, 8, 8, 7, 1, 0, 24, true});
  cases.push_back({24, 24, 40, 37, 40, 36, 0, 1, 24, true});  // more than one 32-row task a line
  for (const CatCase& c : cases) {
    const ConvShape s = shape_of(c);
    INFO(c.a_c << " + " << c.b_c << " channels, " << c.h << "x" << c.w << ", b " << c.b_h << "x" << c.b_w << " at "
                << c.top << "," << c.left << ", oc " << c.oc << " relu " << c.relu);
    const CatInputs m = make_inputs(c, 11 + unsigned(c.b_c));
    REQUIRE(conv_bf16_cat_applicable(s, m.in));
    const std::vector<float> x = copied_concat(c, 11 + unsigned(c.b_c));
    const auto w = random_floats(std::size_t(c.oc) * s.ic * 9, 17);
    std::vector<std::uint16_t> wb(conv_bf16_weight_halves(s));
    pack_conv_bf16_weights(s, w.data(), wb.data());
    const auto bias = bias_of(s);
    const std::size_t ny = std::size_t(s.ocb()) * s.oh() * s.ow() * kBlock;
    std::vector<float> copied(ny, -3.f), in_place(ny, -5.f);
    conv_fwd_bf16_amx(s, x.data(), wb.data(), bias.data(), copied.data());
    conv_fwd_bf16_amx_cat(s, m.in, wb.data(), bias.data(), in_place.data());
    CHECK(same_bits(copied, in_place));
  }
}

TEST_CASE("AMX in place refuses inputs the two maps do not make, and CPUs without AMX", "[kernels][conv_bf16][concat]") {
  const CatCase c{40, 27, 9, 10, 8, 9, 1, 1, 24, false};
  const CatInputs m = make_inputs(c, 7);
  const ConvShape s = shape_of(c);
  check_refusals(conv_bf16_cat_applicable, s, m.in);
  std::vector<float> y(std::size_t(s.ocb()) * s.oh() * s.ow() * kBlock);
  std::vector<std::uint16_t> w(conv_bf16_weight_halves(s));
  ConcatInput bad = m.in;
  bad.top = 5;
  CHECK_THROWS_AS(conv_fwd_bf16_amx_cat(s, bad, w.data(), nullptr, y.data()), std::invalid_argument);
  if (!amx_bf16_available())
    CHECK_THROWS_AS(conv_fwd_bf16_amx_cat(s, m.in, w.data(), nullptr, y.data()), std::logic_error);
}
