// BN, pooling, ConvLSTM update, softmax/DSNT and losses: every ISA against the scalar
// reference, and every backward against central differences of a double-precision forward.
#include <catch2/catch.hpp>

#include <cmath>
#include <functional>

#include "kernels/bn.h"
#include "kernels/heatmap.h"
#include "kernels/loss.h"
#include "kernels/lstm.h"
#include "kernels/pool.h"
#include "test_util.h"

using namespace yelan::kernels;
using yelan::test::random_floats;

namespace {

using Vec = std::vector<float>;

void check_close(const Vec& got, const Vec& want, double rel, double abs_tol, const char* what) {
  REQUIRE(got.size() == want.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    INFO(what << "[" << i << "] got " << got[i] << " want " << want[i]);
    REQUIRE(std::abs(double(got[i]) - want[i]) <= abs_tol + rel * std::abs(double(want[i])));
  }
}

// d/dx_i of f at x by central differences in double, for a sample of indices.
void check_fd(const std::function<double(const std::vector<double>&)>& f, const Vec& x, const Vec& grad,
              std::size_t stride, double tol, const char* what, double rel_step = 1e-5) {
  std::vector<double> xd(x.begin(), x.end());
  for (std::size_t i = 0; i < x.size(); i += stride) {
    const double h = rel_step * std::max(1.0, std::abs(xd[i]));
    auto xp = xd, xm = xd;
    xp[i] += h;
    xm[i] -= h;
    const double fd = (f(xp) - f(xm)) / (2 * h);
    INFO(what << "[" << i << "] analytic " << grad[i] << " numeric " << fd);
    REQUIRE(std::abs(grad[i] - fd) <= tol * (1 + std::abs(fd)));
  }
}

std::vector<double> weights_of(const Vec& w) { return {w.begin(), w.end()}; }

}  // namespace

TEST_CASE("batch norm (+ReLU) variants match the reference and finite differences", "[kernels][bn]") {
  for (BnShape s : {BnShape{1, 1, 1}, BnShape{2, 1, 7}, BnShape{3, 2, 17}, BnShape{1, 2, 33 * 44}}) {
    const std::size_t N = std::size_t(s.n) * s.cb * s.pixels * 16, C = std::size_t(s.cb) * 16;
    const Vec x = random_floats(N, 1, -2.f, 3.f), dy = random_floats(N, 2);
    const Vec gamma = random_floats(C, 3, 0.5f, 1.5f), beta = random_floats(C, 4);
    const float eps = 1e-5f;
    for (bool relu : {false, true}) {
      Vec mean_r(C), var_r(C), y_r(N), dx_r(N), dg_r(C), db_r(C);
      bn_scalar.stats(s, x.data(), mean_r.data(), var_r.data());
      bn_scalar.fwd(s, x.data(), mean_r.data(), var_r.data(), gamma.data(), beta.data(), eps, relu, y_r.data());
      bn_scalar.bwd(s, x.data(), y_r.data(), dy.data(), mean_r.data(), var_r.data(), gamma.data(), eps, relu,
                    dx_r.data(), dg_r.data(), db_r.data());
      for (Isa isa : yelan::test::supported_isas()) {
        INFO("isa " << isa_name(isa) << " n" << s.n << " cb" << s.cb << " px" << s.pixels << " relu " << relu);
        const BnKernels& k = bn_kernels(isa);
        Vec mean(C), var(C), y(N), dx(N), dg(C), db(C);
        k.stats(s, x.data(), mean.data(), var.data());
        check_close(mean, mean_r, 1e-5, 1e-6, "mean");
        check_close(var, var_r, 1e-5, 1e-6, "var");
        k.fwd(s, x.data(), mean_r.data(), var_r.data(), gamma.data(), beta.data(), eps, relu, y.data());
        check_close(y, y_r, 1e-5, 2e-6, "y");
        k.bwd(s, x.data(), y_r.data(), dy.data(), mean_r.data(), var_r.data(), gamma.data(), eps, relu, dx.data(),
              dg.data(), db.data());
        check_close(dx, dx_r, 1e-4, 2e-5, "dx");
        check_close(dg, dg_r, 1e-4, 1e-4, "dgamma");
        check_close(db, db_r, 1e-4, 1e-4, "dbeta");
      }
      if (s.pixels * s.n < 2) continue;  // one value per channel: the gradient is all eps
      // L = sum dy * bn(x) in double, batch statistics recomputed for every perturbation.
      const auto w = weights_of(dy);
      auto loss_x = [&](const std::vector<double>& xx) {
        double L = 0;
        for (int b = 0; b < s.cb; ++b)
          for (int l = 0; l < 16; ++l) {
            double m = 0, v = 0;
            const double M = double(s.n) * s.pixels;
            auto at = [&](int n, std::size_t p) { return ((std::size_t(n) * s.cb + b) * s.pixels + p) * 16 + l; };
            for (int n = 0; n < s.n; ++n)
              for (std::size_t p = 0; p < s.pixels; ++p) m += xx[at(n, p)] / M;
            for (int n = 0; n < s.n; ++n)
              for (std::size_t p = 0; p < s.pixels; ++p) v += (xx[at(n, p)] - m) * (xx[at(n, p)] - m) / M;
            for (int n = 0; n < s.n; ++n)
              for (std::size_t p = 0; p < s.pixels; ++p) {
                double yv = (xx[at(n, p)] - m) / std::sqrt(v + eps) * gamma[b * 16 + l] + beta[b * 16 + l];
                if (relu && yv < 0) yv = 0;
                L += w[at(n, p)] * yv;
              }
          }
        return L;
      };
      check_fd(loss_x, x, dx_r, s.pixels > 100 ? 97 : 3, 2e-3, "bn dx");
    }
  }
}

TEST_CASE("max and global average pooling match the reference and finite differences", "[kernels][pool]") {
  for (PoolShape s : {PoolShape{2, 7, 5, 3, 2, 1}, PoolShape{1, 1, 1, 3, 2, 1}, PoolShape{1, 33, 44, 3, 2, 1},
                      PoolShape{3, 6, 6, 2, 2, 0}, PoolShape{1, 17, 9, 3, 1, 1}}) {
    REQUIRE(s.valid());
    const std::size_t NI = std::size_t(s.planes) * s.ih * s.iw * 16, NO = std::size_t(s.planes) * s.oh() * s.ow() * 16;
    const Vec x = random_floats(NI, 7), dy = random_floats(NO, 8);
    Vec y_r(NO), dx_r(NI);
    std::vector<std::int32_t> a_r(NO);
    pool_scalar.max_fwd(s, x.data(), y_r.data(), a_r.data());
    pool_scalar.max_bwd(s, dy.data(), a_r.data(), dx_r.data());
    for (Isa isa : yelan::test::supported_isas()) {
      INFO("isa " << isa_name(isa) << " " << s.ih << "x" << s.iw << " k" << s.k << " s" << s.stride);
      Vec y(NO), dx(NI, 5.f);
      std::vector<std::int32_t> a(NO);
      pool_kernels(isa).max_fwd(s, x.data(), y.data(), a.data());
      CHECK(y == y_r);
      CHECK(a == a_r);
      pool_kernels(isa).max_bwd(s, dy.data(), a.data(), dx.data());
      CHECK(dx == dx_r);
    }
    auto loss = [&](const std::vector<double>& xx) {
      double L = 0;
      for (int p = 0; p < s.planes; ++p)
        for (int oh = 0; oh < s.oh(); ++oh)
          for (int ow = 0; ow < s.ow(); ++ow)
            for (int l = 0; l < 16; ++l) {
              double m = -1e300;
              for (int kh = 0; kh < s.k; ++kh)
                for (int kw = 0; kw < s.k; ++kw) {
                  const int ih = oh * s.stride - s.pad + kh, iw = ow * s.stride - s.pad + kw;
                  if (ih >= 0 && ih < s.ih && iw >= 0 && iw < s.iw)
                    m = std::max(m, xx[((std::size_t(p) * s.ih + ih) * s.iw + iw) * 16 + l]);
                }
              L += m * dy[((std::size_t(p) * s.oh() + oh) * s.ow() + ow) * 16 + l];
            }
      return L;
    };
    check_fd(loss, x, dx_r, NI > 2000 ? 37 : 1, 1e-4, "maxpool dx", 1e-8);  // no window max may change
  }
  for (std::size_t px : {1u, 7u, 1452u}) {
    const Vec x = random_floats(3 * px * 16, 9), g = random_floats(3 * 16, 10);
    Vec y_r(48), dx_r(x.size());
    pool_scalar.avg_global_fwd(3, px, x.data(), y_r.data());
    pool_scalar.avg_global_bwd(3, px, g.data(), dx_r.data());
    for (Isa isa : yelan::test::supported_isas()) {
      Vec y(48), dx(x.size());
      pool_kernels(isa).avg_global_fwd(3, px, x.data(), y.data());
      check_close(y, y_r, 1e-6, 1e-7, "avg y");
      pool_kernels(isa).avg_global_bwd(3, px, g.data(), dx.data());
      CHECK(dx == dx_r);
    }
    auto loss = [&](const std::vector<double>& xx) {
      double L = 0;
      for (std::size_t i = 0; i < xx.size(); ++i) L += xx[i] / double(px) * g[(i / (px * 16)) * 16 + i % 16];
      return L;
    };
    check_fd(loss, x, dx_r, px > 100 ? 101 : 1, 1e-4, "avgpool dx");
  }
}

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

TEST_CASE("spatial softmax and DSNT match the reference and finite differences", "[kernels][heatmap]") {
  for (auto [planes, h, w] : {std::tuple{1, 1, 1}, std::tuple{2, 7, 5}, std::tuple{1, 33, 44}}) {
    const std::size_t px = std::size_t(h) * w, N = planes * px * 16;
    const Vec x = random_floats(N, 21, -4.f, 4.f), dy = random_floats(N, 22), dout = random_floats(planes * 32, 23);
    Vec y_r(N), dx_r(N), o_r(planes * 32), dd_r(N);
    heatmap_scalar.softmax_fwd(planes, px, x.data(), y_r.data());
    heatmap_scalar.softmax_bwd(planes, px, y_r.data(), dy.data(), dx_r.data());
    heatmap_scalar.dsnt_fwd(planes, h, w, y_r.data(), o_r.data());
    heatmap_scalar.dsnt_bwd(planes, h, w, dout.data(), dd_r.data());
    for (Isa isa : yelan::test::supported_isas()) {
      INFO("isa " << isa_name(isa) << " " << h << "x" << w);
      const HeatmapKernels& k = heatmap_kernels(isa);
      Vec y(N), dx(N), o(planes * 32), dd(N);
      k.softmax_fwd(planes, px, x.data(), y.data());
      check_close(y, y_r, 1e-5, 1e-9, "softmax");
      k.softmax_bwd(planes, px, y_r.data(), dy.data(), dx.data());
      check_close(dx, dx_r, 1e-4, 1e-7, "softmax dx");
      k.dsnt_fwd(planes, h, w, y_r.data(), o.data());
      check_close(o, o_r, 1e-5, 1e-6, "dsnt");
      k.dsnt_bwd(planes, h, w, dout.data(), dd.data());
      check_close(dd, dd_r, 1e-6, 1e-7, "dsnt dy");
    }
    // DSNT(softmax(x)) against dout: the chain through both backward kernels.
    Vec chain(N);
    heatmap_scalar.softmax_bwd(planes, px, y_r.data(), dd_r.data(), chain.data());
    auto loss = [&](const std::vector<double>& xx) {
      double L = 0;
      for (int p = 0; p < planes; ++p)
        for (int l = 0; l < 16; ++l) {
          auto at = [&](std::size_t i) { return (p * px + i) * 16 + l; };
          double m = -1e300, s = 0, ex = 0, ey = 0;
          for (std::size_t i = 0; i < px; ++i) m = std::max(m, xx[at(i)]);
          for (std::size_t i = 0; i < px; ++i) s += std::exp(xx[at(i)] - m);
          for (std::size_t i = 0; i < px; ++i) {
            const double v = std::exp(xx[at(i)] - m) / s;
            ex += v * dsnt_coordinate(int(i % w), w);
            ey += v * dsnt_coordinate(int(i / w), h);
          }
          L += ex * dout[(p * 2) * 16 + l] + ey * dout[(p * 2 + 1) * 16 + l];
        }
      return L;
    };
    check_fd(loss, x, chain, px > 100 ? 53 : 1, 1e-4, "dsnt(softmax) dx");
  }
  CHECK(dsnt_coordinate(0, 1) == 0.f);
  CHECK(dsnt_coordinate(0, 4) == -0.75f);
  CHECK(dsnt_coordinate(3, 4) == 0.75f);
}

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
