// The ConvLSTM point-wise update: every ISA against the scalar reference, and the backward against
// central differences of a double-precision forward.
#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include "kernels/lstm.h"
#include "kernel_checks.h"

TEST_CASE("ConvLSTM point-wise update matches the reference and finite differences", "[kernels][lstm]") {
  for (LstmShape s : {LstmShape{1, 1, 1}, LstmShape{2, 1, 7}, LstmShape{1, 2, 33}}) {
    const std::size_t E = std::size_t(s.hb) * s.pixels * 16, NS = s.n * E, NG = 4 * NS;
    const Vec gates = random_floats(NG, 11, -3.f, 3.f), c_prev = random_floats(NS, 12, -2.f, 2.f);
    const Vec dh = random_floats(NS, 13), dc = random_floats(NS, 14);
    Vec act_r(NG), c_r(NS), h_r(NS), t_r(NS), dg_r(NG), dcp_r(NS);
    lstm_scalar.fwd(s, gates.data(), c_prev.data(), act_r.data(), c_r.data(), h_r.data(), t_r.data());
    lstm_scalar.bwd(s, act_r.data(), c_prev.data(), t_r.data(), dh.data(), dc.data(), dg_r.data(), dcp_r.data());
    for (Isa isa : yelan::test::supported_isas()) {
      INFO("isa " << isa_name(isa) << " n" << s.n << " hb" << s.hb << " px" << s.pixels);
      Vec act(NG), c(NS), h(NS), t(NS), dg(NG), dcp(NS);
      lstm_kernels(isa).fwd(s, gates.data(), c_prev.data(), act.data(), c.data(), h.data(), t.data());
      check_close(act, act_r, 0, 4e-7, "act");
      check_close(c, c_r, 0, 1e-6, "c");
      check_close(h, h_r, 0, 1e-6, "h");
      lstm_kernels(isa).bwd(s, act_r.data(), c_prev.data(), t_r.data(), dh.data(), dc.data(), dg.data(), dcp.data());
      check_close(dg, dg_r, 1e-5, 1e-6, "dgates");
      check_close(dcp, dcp_r, 1e-5, 1e-6, "dc_prev");
      Vec h0(NS), c0(NS), h_z(NS), scratch_a(NG), scratch_t(NS);  // null state == zero state
      Vec zeros(NS, 0.f);
      lstm_kernels(isa).fwd(s, gates.data(), nullptr, act.data(), c0.data(), h0.data(), t.data());
      lstm_scalar.fwd(s, gates.data(), zeros.data(), scratch_a.data(), c.data(), h_z.data(), scratch_t.data());
      check_close(h0, h_z, 0, 1e-6, "h with null state");
    }
    // L = sum dh * h + dc * c as a function of gates and of c_prev, in double.
    auto forward = [&](const std::vector<double>& g, const std::vector<double>& cp) {
      double L = 0;
      for (int n = 0; n < s.n; ++n)
        for (std::size_t e = 0; e < E; ++e) {
          auto G = [&](int k) { return g[(std::size_t(n) * 4 + k) * E + e]; };
          auto sg = [](double v) { return 1 / (1 + std::exp(-v)); };
          const std::size_t k = n * E + e;
          const double cn = sg(G(1)) * cp[k] + sg(G(0)) * std::tanh(G(3));
          L += dh[k] * sg(G(2)) * std::tanh(cn) + dc[k] * cn;
        }
      return L;
    };
    const std::vector<double> cpd(c_prev.begin(), c_prev.end()), gd(gates.begin(), gates.end());
    check_fd([&](const std::vector<double>& g) { return forward(g, cpd); }, gates, dg_r, 3, 1e-4, "dgates");
    check_fd([&](const std::vector<double>& cp) { return forward(gd, cp); }, c_prev, dcp_r, 3, 1e-4, "dc_prev");
  }
}
