#include <catch2/catch.hpp>

#include <cmath>
#include <limits>

#include "kernels/eltwise.h"
#include "test_util.h"

using namespace yelan::kernels;
using yelan::test::random_floats;

namespace {
// Odd lengths around every vector width (4, 8, 16) and their unrolls.
const std::size_t kLengths[] = {0, 1, 3, 4, 7, 8, 9, 15, 16, 17, 31, 32, 33, 63, 1000, 4099};
constexpr float kGuard = 12345.f;
}  // namespace

TEST_CASE("eltwise variants match the scalar reference on odd lengths and offsets", "[kernels][eltwise]") {
  const EltwiseKernels& ref = eltwise_scalar;
  for (Isa isa : yelan::test::supported_isas()) {
    const EltwiseKernels& k = eltwise_kernels(isa);
    REQUIRE(k.isa == isa);
    for (std::size_t n : kLengths) {
      for (std::size_t offset : {0u, 1u, 3u}) {  // misaligned starts
        INFO("isa " << isa_name(isa) << " n " << n << " offset " << offset);
        auto a = random_floats(n + offset + 1, 1 + n);
        auto b = random_floats(n + offset + 1, 2 + n);
        a[offset] = 0.f;  // relu's boundary
        if (n > 2) a[offset + 2] = -0.f;
        std::vector<float> y(n + offset + 1, kGuard), y_ref(n + offset + 1, kGuard);

        k.add(a.data() + offset, b.data() + offset, y.data() + offset, n);
        ref.add(a.data() + offset, b.data() + offset, y_ref.data() + offset, n);
        CHECK(y == y_ref);  // one rounding, so bit-identical

        k.relu(a.data() + offset, y.data() + offset, n);
        ref.relu(a.data() + offset, y_ref.data() + offset, n);
        CHECK(y == y_ref);

        k.relu_backward(a.data() + offset, b.data() + offset, y.data() + offset, n);
        ref.relu_backward(a.data() + offset, b.data() + offset, y_ref.data() + offset, n);
        CHECK(y == y_ref);

        y = b;
        y_ref = b;
        k.axpy(0.37f, a.data() + offset, y.data() + offset, n);
        ref.axpy(0.37f, a.data() + offset, y_ref.data() + offset, n);
        for (std::size_t i = 0; i < y.size(); ++i)  // FMA rounds once, mul+add twice
          REQUIRE(std::abs(y[i] - y_ref[i]) <= 2e-7f * (1.f + std::abs(y_ref[i])));

        double abs_sum = 0;
        for (std::size_t i = 0; i < n; ++i) abs_sum += std::abs(double(a[offset + i]) * b[offset + i]);
        const float d = k.dot(a.data() + offset, b.data() + offset, n);
        const float d_ref = ref.dot(a.data() + offset, b.data() + offset, n);
        CHECK(std::abs(d - d_ref) <= 1e-6 * double(n + 1) * (abs_sum + 1e-30));

        CHECK(y[offset + n] == b[offset + n]);  // nothing written past the end
      }
    }
  }
}

TEST_CASE("eltwise kernels never write past n", "[kernels][eltwise]") {
  for (Isa isa : yelan::test::supported_isas()) {
    const EltwiseKernels& k = eltwise_kernels(isa);
    for (std::size_t n : kLengths) {
      INFO("isa " << isa_name(isa) << " n " << n);
      auto a = random_floats(n + 16, 7);
      std::vector<float> y(n + 16, kGuard);
      k.relu(a.data(), y.data(), n);
      for (std::size_t i = n; i < y.size(); ++i) REQUIRE(y[i] == kGuard);
      k.add(a.data(), a.data(), y.data(), n);
      for (std::size_t i = n; i < y.size(); ++i) REQUIRE(y[i] == kGuard);
    }
  }
}

TEST_CASE("relu backward passes no gradient at or below zero, nor through NaN", "[kernels][eltwise]") {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<float> x = {-1.f, 0.f, -0.f, 1e-30f, nan, 2.f, -3.f, 4.f, 0.f, 5.f, 6.f, -7.f, 8.f, nan, 9.f, 1.f, -1.f};
  std::vector<float> dy(x.size(), 3.f);
  for (Isa isa : yelan::test::supported_isas()) {
    std::vector<float> dx(x.size(), kGuard);
    eltwise_kernels(isa).relu_backward(x.data(), dy.data(), dx.data(), x.size());
    for (std::size_t i = 0; i < x.size(); ++i) {
      INFO("isa " << isa_name(isa) << " i " << i << " x " << x[i]);
      CHECK(dx[i] == (x[i] > 0.f ? 3.f : 0.f));
    }
  }
}
