// Checks shared by the kernel tests: element-wise closeness, and central differences in
// double for backward passes.
#pragma once
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <vector>

#include "test_util.h"

namespace yelan::test {

using Vec = std::vector<float>;

inline void check_close(const Vec& got, const Vec& want, double rel, double abs_tol, const char* what) {
  REQUIRE(got.size() == want.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    INFO(what << "[" << i << "] got " << got[i] << " want " << want[i]);
    REQUIRE(std::abs(double(got[i]) - want[i]) <= abs_tol + rel * std::abs(double(want[i])));
  }
}

// d/dx_i of f at x by central differences in double, for a sample of indices.
inline void check_fd(const std::function<double(const std::vector<double>&)>& f, const Vec& x, const Vec& grad,
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

inline std::vector<double> weights_of(const Vec& w) { return {w.begin(), w.end()}; }

}  // namespace yelan::test

// What every kernel test file uses, said once here.
namespace yelan::kernels {}
using namespace yelan::kernels;
using yelan::test::check_close;
using yelan::test::check_fd;
using yelan::test::random_floats;
using yelan::test::weights_of;
using Vec = std::vector<float>;
