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

// Two convolutions in a row: ic -> mid (kernel k1, pad p1) -> oc (k2, p2), n images of h x w;
// a_c > 0: the first's input is a_c channels of the map and ic - a_c of a second one (b_h x b_w
// at top, left), read in place.
struct PairCase {
  int n, ic, h, w, mid, k1, p1, oc, k2, p2;
  int a_c = 0, b_h = 0, b_w = 0, top = 0, left = 0;
};

ConvShape conv(int n, int ic, int h, int w, int oc, int k, int pad, bool relu) {
  ConvShape s;
  s.n = n; s.ic = ic; s.ih = h; s.iw = w; s.oc = oc; s.kh = s.kw = k; s.pad_h = s.pad_w = pad; s.relu = relu;
  return s;
}

std::vector<float> bias_for(const ConvShape& s, unsigned seed) {
  std::vector<float> bias(std::size_t(s.ocb()) * kBlock, 0.f);
  const auto b = random_floats(std::size_t(s.oc), seed);
  std::copy(b.begin(), b.end(), bias.begin());
  return bias;
}

std::vector<std::uint16_t> packed(const ConvShape& s, unsigned seed) {
  const auto w = random_floats(std::size_t(s.oc) * s.ic * s.kh * s.kw, seed);
  std::vector<std::uint16_t> wb(conv_bf16_weight_halves(s));
  pack_conv_bf16_weights(s, w.data(), wb.data());
  return wb;
}

}  // namespace

// The pair against two calls of the single kernel: stage 1's shapes (6 -> 24 -> 24, 24 + 24 ->
// 24 -> 24 joined in place), lines longer than a 32-row task, odd channel counts (an odd number
// of blocks leaves half a pair, in the middle map too), the two convolutions' paddings and
// kernels different (the middle map's plane has its own borders), no padding, two images.
TEST_CASE("two AMX convolutions in a row through a bf16 plane equal two calls, bit for bit", "[kernels][conv_bf16][pair]") {
  yelan::test::amx_or_skip();
  const PairCase cases[] = {
      {1, 6, 13, 17, 24, 3, 1, 24, 3, 1},
      {1, 24, 40, 37, 24, 3, 1, 24, 3, 1},
      {1, 48, 9, 11, 48, 3, 1, 48, 3, 1},
      {2, 33, 7, 9, 70, 5, 2, 17, 3, 1},
      {1, 16, 10, 12, 40, 3, 0, 8, 3, 1},
      {1, 20, 6, 8, 16, 1, 0, 24, 3, 1},
      {1, 48, 17, 22, 24, 3, 1, 24, 3, 1, 24, 17, 21, 0, 1},
      {1, 67, 9, 8, 24, 3, 1, 13, 3, 1, 40, 8, 7, 1, 0},
  };
  for (const PairCase& c : cases)
    for (bool relu : {false, true}) {
      INFO("n " << c.n << " ic " << c.ic << " (a " << c.a_c << ") " << c.h << "x" << c.w << " -> " << c.mid << " k"
                << c.k1 << " p" << c.p1 << " -> " << c.oc << " k" << c.k2 << " p" << c.p2 << " relu " << relu);
      const ConvShape s1 = conv(c.n, c.ic, c.h, c.w, c.mid, c.k1, c.p1, relu);
      const ConvShape s2 = conv(c.n, c.mid, s1.oh(), s1.ow(), c.oc, c.k2, c.p2, !relu);
      REQUIRE(conv_bf16_pair_applicable(s1, s2));
      const auto w1 = packed(s1, 3), w2 = packed(s2, 4);
      const auto b1 = bias_for(s1, 5), b2 = bias_for(s2, 6);
      // The input: one map, or a (a_c channels) and b (the rest, smaller, at its offset) and their copy.
      std::vector<float> x, a, b;
      ConcatInput in;
      if (c.a_c == 0) {
        x = to_blocked(random_floats(std::size_t(c.n) * c.ic * c.h * c.w, 7), c.n, c.ic, c.h, c.w);
        in.a = x.data();
        in.a_c = c.ic;
      } else {
        const int b_c = c.ic - c.a_c;
        const auto pa = random_floats(std::size_t(c.a_c) * c.h * c.w, 8);
        const auto pb = random_floats(std::size_t(b_c) * c.b_h * c.b_w, 9);
        std::vector<float> plain(std::size_t(c.ic) * c.h * c.w, 0.f);
        std::copy(pa.begin(), pa.end(), plain.begin());
        for (int ch = 0; ch < b_c; ++ch)
          for (int h = 0; h < c.b_h; ++h)
            for (int w = 0; w < c.b_w; ++w)
              plain[(std::size_t(c.a_c + ch) * c.h + h + c.top) * c.w + w + c.left] =
                  pb[(std::size_t(ch) * c.b_h + h) * c.b_w + w];
        x = to_blocked(plain, 1, c.ic, c.h, c.w);
        a = to_blocked(pa, 1, c.a_c, c.h, c.w);
        b = to_blocked(pb, 1, b_c, c.b_h, c.b_w);
        in = {a.data(), c.a_c, b.data(), b_c, c.b_h, c.b_w, c.top, c.left};
        REQUIRE(conv_bf16_cat_applicable(s1, in));
      }
      std::vector<float> mid(std::size_t(c.n) * s1.ocb() * s1.oh() * s1.ow() * kBlock, -2.f);
      const std::size_t ny = std::size_t(c.n) * s2.ocb() * s2.oh() * s2.ow() * kBlock;
      std::vector<float> two_calls(ny, -3.f), pair(ny, -5.f);
      conv_fwd_bf16_amx(s1, x.data(), w1.data(), b1.data(), mid.data());
      conv_fwd_bf16_amx(s2, mid.data(), w2.data(), b2.data(), two_calls.data());
      conv_pair_fwd_bf16_amx(s1, in, w1.data(), b1.data(), s2, w2.data(), b2.data(), pair.data());
      CHECK(std::memcmp(two_calls.data(), pair.data(), ny * sizeof(float)) == 0);
    }
}

TEST_CASE("the AMX pair refuses convolutions that do not chain, inputs that do not fit, and CPUs without AMX", "[kernels][conv_bf16][pair]") {
  const ConvShape s1 = conv(1, 24, 9, 10, 24, 3, 1, true), s2 = conv(1, 24, 9, 10, 16, 3, 1, false);
  CHECK(conv_bf16_pair_applicable(s1, s2));
  auto refused = [&](auto edit) {
    ConvShape a = s1, b = s2;
    edit(a, b);
    return !conv_bf16_pair_applicable(a, b);
  };
  CHECK(refused([](ConvShape&, ConvShape& b) { b.ic = 16; }));      // the second does not take the first's channels
  CHECK(refused([](ConvShape&, ConvShape& b) { b.ih = 8; }));       // nor its size
  CHECK(refused([](ConvShape& a, ConvShape&) { a.pad_h = 0; }));    // (the first's output shrinks)
  CHECK(refused([](ConvShape& a, ConvShape&) { a.stride = 2; }));   // strided
  CHECK(refused([](ConvShape&, ConvShape& b) { b.n = 2; }));
  std::vector<float> x(std::size_t(2) * 9 * 10 * kBlock), y(std::size_t(9) * 10 * kBlock);
  std::vector<std::uint16_t> w1(conv_bf16_weight_halves(s1)), w2(conv_bf16_weight_halves(s2));
  ConvShape bad = s2;
  bad.ic = 16;
  const ConcatInput plain{x.data(), 24};
  CHECK_THROWS_AS(conv_pair_fwd_bf16_amx(s1, plain, w1.data(), nullptr, bad, w2.data(), nullptr, y.data()),
                  std::invalid_argument);
  const ConcatInput short_of_channels{x.data(), 16};
  CHECK_THROWS_AS(conv_pair_fwd_bf16_amx(s1, short_of_channels, w1.data(), nullptr, s2, w2.data(), nullptr, y.data()),
                  std::invalid_argument);
  if (!amx_bf16_available())
    CHECK_THROWS_AS(conv_pair_fwd_bf16_amx(s1, plain, w1.data(), nullptr, s2, w2.data(), nullptr, y.data()),
                    std::logic_error);
}
