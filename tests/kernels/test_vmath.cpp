#include <catch2/catch.hpp>

#include <cmath>
#include <cstring>
#include <limits>
#include <random>

#include "kernels/vmath.h"
#include "test_util.h"

using namespace yelan::kernels;

namespace {

std::vector<float> sweep(float lo, float hi, std::size_t n) {
  std::vector<float> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = lo + (hi - lo) * float(i) / float(n - 1);
  return v;
}

template <class Ref>
double max_error(void (*f)(const float*, float*, std::size_t), const std::vector<float>& x, Ref ref,
                 bool relative) {
  std::vector<float> y(x.size());
  f(x.data(), y.data(), x.size());
  double worst = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double want = ref(double(x[i]));
    const double err = std::abs(y[i] - want) / (relative ? std::abs(want) : 1.0);
    worst = std::max(worst, err);
  }
  return worst;
}

std::vector<float> random_positive_normals(std::size_t n) {
  std::mt19937 rng(5);
  std::uniform_int_distribution<std::uint32_t> bits(0x00800000u, 0x7f7fffffu);
  std::vector<float> v(n);
  for (auto& f : v) {
    const std::uint32_t b = bits(rng);
    std::memcpy(&f, &b, 4);
  }
  return v;
}

}  // namespace

TEST_CASE("vector exp/log/sigmoid/tanh stay within their stated error bounds", "[kernels][vmath]") {
  const auto xs_exp = sweep(-87.f, 88.f, 200003);  // odd count: exercises the tail path
  const auto xs_log = random_positive_normals(200001);
  const auto xs_act = sweep(-20.f, 20.f, 100001);
  for (Isa isa : yelan::test::supported_isas()) {
    const VmathKernels& k = vmath_kernels(isa);
    INFO("isa " << isa_name(isa));
    const double e_exp = max_error(k.exp, xs_exp, [](double v) { return std::exp(v); }, true);
    const double e_log = max_error(k.log, xs_log, [](double v) { return std::log(v); }, false);
    const double e_log_rel = max_error(k.log, sweep(0.5f, 2.f, 100001), [](double v) { return std::log(v); }, false);
    const double e_sig = max_error(k.sigmoid, xs_act, [](double v) { return 1 / (1 + std::exp(-v)); }, false);
    const double e_tanh = max_error(k.tanh, xs_act, [](double v) { return std::tanh(v); }, false);
    INFO("exp rel " << e_exp << ", log abs " << e_log << " (near 1: " << e_log_rel << "), sigmoid abs " << e_sig
                    << ", tanh abs " << e_tanh);
    CHECK(e_exp <= 2.5e-7);
    CHECK(e_log <= 2e-7 * 90);  // |log x| <= 88.8 for normal floats: relative 2e-7
    CHECK(e_log_rel <= 1.5e-7);
    CHECK(e_sig <= 3e-7);
    CHECK(e_tanh <= 3e-7);
  }
}

TEST_CASE("vector math handles special values like the C library", "[kernels][vmath]") {
  const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
  const std::vector<float> x = {0.f, -0.f, 1.f, -1.f, 100.f, -100.f, inf, -inf, nan, 1e-40f, 89.f, -104.f};
  for (Isa isa : yelan::test::supported_isas()) {
    const VmathKernels& k = vmath_kernels(isa);
    std::vector<float> e(x.size()), l(x.size()), s(x.size()), t(x.size());
    k.exp(x.data(), e.data(), x.size());
    k.log(x.data(), l.data(), x.size());
    k.sigmoid(x.data(), s.data(), x.size());
    k.tanh(x.data(), t.data(), x.size());
    INFO("isa " << isa_name(isa));
    CHECK(e[0] == 1.f);
    CHECK(e[4] == inf);
    CHECK((e[5] >= 0.f && e[5] < 1e-37f));  // the C library gives a subnormal, SIMD flushes to 0
    CHECK(e[6] == inf);
    CHECK(e[7] == 0.f);
    CHECK(std::isnan(e[8]));
    CHECK(e[10] == inf);
    CHECK(l[0] == -inf);
    CHECK(l[2] == 0.f);
    CHECK(std::isnan(l[3]));
    CHECK(l[6] == inf);
    CHECK(std::isnan(l[8]));
    CHECK(std::abs(l[9] - std::log(1e-40)) < 1e-4);  // subnormal input
    CHECK(s[0] == 0.5f);
    CHECK(s[4] == 1.f);
    CHECK((s[5] >= 0.f && s[5] < 1e-37f));
    CHECK(std::isnan(s[8]));
    CHECK(t[0] == 0.f);
    CHECK(t[4] == 1.f);
    CHECK(t[5] == -1.f);
    CHECK(t[6] == 1.f);
    CHECK(t[7] == -1.f);
    CHECK(std::isnan(t[8]));
  }
}
