// Max and global average pooling: every ISA against the scalar reference, and the backward against
// central differences of a double-precision forward.
#include <catch2/catch.hpp>

#include <cmath>
#include <vector>

#include "kernels/pool.h"
#include "kernel_checks.h"

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
