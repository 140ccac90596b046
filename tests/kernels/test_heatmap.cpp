// Spatial softmax and DSNT: every ISA against the scalar reference, and the backward against
// central differences of a double-precision forward.
#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include "kernels/heatmap.h"
#include "kernel_checks.h"

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
