// Batch norm (+ReLU): every ISA against the scalar reference, and the backward against
// central differences of a double-precision forward.
#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include "kernels/bn.h"
#include "kernel_checks.h"

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
