// BCE-with-logits and Jensen-Shannon: every ISA against the scalar reference, and the backward against
// central differences of a double-precision forward.
#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include "kernels/loss.h"
#include "kernel_checks.h"

TEST_CASE("BCE-with-logits and JSD match the reference and finite differences", "[kernels][loss]") {
  for (std::size_t n : {1u, 7u, 17u, 1000u, 4099u}) {
    const Vec x = random_floats(n, 31, -8.f, 8.f), t = random_floats(n, 32, 0.f, 1.f);
    Vec p = random_floats(n, 33, 0.f, 1.f), q = random_floats(n, 34, 0.f, 1.f);
    p[0] = 0.f;  // an empty bin
    Vec gb_r(n), gj_r(n);
    const double lb_r = loss_scalar.bce_logits(x.data(), t.data(), n, gb_r.data());
    const double lj_r = loss_scalar.jsd(p.data(), q.data(), n, 1e-12f, gj_r.data());
    for (Isa isa : yelan::test::supported_isas()) {
      INFO("isa " << isa_name(isa) << " n " << n);
      Vec gb(n), gj(n);
      CHECK(std::abs(loss_kernels(isa).bce_logits(x.data(), t.data(), n, gb.data()) - lb_r) <= 1e-5 * lb_r);
      check_close(gb, gb_r, 0, 5e-7, "bce dx");
      CHECK(std::abs(loss_kernels(isa).jsd(p.data(), q.data(), n, 1e-12f, gj.data()) - lj_r) <= 1e-5 * lj_r + 1e-9);
      check_close(gj, gj_r, 1e-5, 1e-6, "jsd dp");
    }
    auto bce = [&](const std::vector<double>& xx) {
      double L = 0;
      for (std::size_t i = 0; i < n; ++i) L += std::log1p(std::exp(-xx[i])) + (1 - t[i]) * xx[i];
      return L;
    };
    check_fd(bce, x, gb_r, n > 100 ? 31 : 1, 1e-5, "bce");
    auto jsd = [&](const std::vector<double>& pp) {
      double L = 0;
      for (std::size_t i = 0; i < n; ++i) {
        const double m = 0.5 * (pp[i] + q[i]);
        if (pp[i] > 0) L += 0.5 * pp[i] * std::log(pp[i] / m);
        L += 0.5 * q[i] * std::log(q[i] / m);
      }
      return L;
    };
    Vec p_interior = p;
    for (auto& v : p_interior) v = std::max(v, 1e-2f);  // keep p well above the step
    Vec g_int(n);
    loss_scalar.jsd(p_interior.data(), q.data(), n, 1e-12f, g_int.data());
    check_fd(jsd, p_interior, g_int, n > 100 ? 31 : 1, 1e-5, "jsd");
  }
}
