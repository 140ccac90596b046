// Finite-difference helpers for layer and block tests: blocked activations with storage,
// and central differences that skip samples where a ReLU kink was crossed (the
// difference quotient then changes with the step, so two steps disagree).
#pragma once
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>

#include "layers/param.h"
#include "test_util.h"

namespace yelan::test {

struct Owned {
  layers::Floats mem;
  layers::Act act;
  Owned(int n, int c, int h, int w, unsigned seed = 0) {
    act = {nullptr, n, c, h, w};
    mem = layers::Floats(act.floats());
    act.data = mem.data();
    if (seed) {
      std::mt19937 rng(seed);
      std::uniform_real_distribution<float> u(-1.f, 1.f);
      for_each_real([&](std::size_t i) { mem[i] = u(rng); });
    }
  }
  explicit Owned(const layers::Act& s, unsigned seed = 0) : Owned(s.n, s.c, s.h, s.w, seed) {}
  template <class F>
  void for_each_real(F&& f) const {
    for (int n = 0; n < act.n; ++n)
      for (int c = 0; c < act.c; ++c)
        for (std::size_t p = 0; p < act.pixels(); ++p)
          f(((std::size_t(n) * act.cb() + c / 16) * act.pixels() + p) * 16 + c % 16);
  }
};

inline double dot(const layers::Act& a, const layers::Act& b) {
  double s = 0;
  for (std::size_t i = 0; i < a.floats(); ++i) s += double(a.data[i]) * b.data[i];
  return s;
}

// Checks grad[i] = dL/dv[i] for every `stride`-th entry of v. Samples whose quotient
// changes between steps h and h/2 crossed a kink and are skipped; at least `min_fraction`
// must count (a BN shift moves a whole channel, so its samples cross kinks most often).
// min_agree < 1: that share of the checked samples must agree, not each (through many ReLU
// layers a kink within a step slips past the two-step test on a few samples).
// Returns how many samples were checked.
inline int check_fd_kinked(const std::function<double()>& loss, float* v, const float* grad,
                            const std::vector<std::size_t>& indices, double h, double tol, const char* what,
                            double min_fraction = 0.5, double min_agree = 1) {
  int checked = 0, skipped = 0, agreed = 0;
  for (std::size_t i : indices) {
    const float saved = v[i];
    auto quotient = [&](double step) {
      v[i] = saved + float(step);
      const double lp = loss();
      v[i] = saved - float(step);
      const double lm = loss();
      v[i] = saved;
      return (lp - lm) / (2 * step);
    };
    const double f1 = quotient(h), f2 = quotient(h / 2);
    if (std::abs(f1 - f2) > 0.2 * tol * (1 + std::abs(f1))) {  // much stricter than the check
      ++skipped;
      continue;
    }
    ++checked;
    const bool ok = std::abs(grad[i] - f1) <= tol * (1 + std::abs(f1));
    agreed += ok;
    if (min_agree >= 1) {
      INFO(what << "[" << i << "] analytic " << grad[i] << " numeric " << f1);
      REQUIRE(ok);
    }
  }
  INFO(what << ": " << checked << " checked, " << skipped << " skipped at kinks, " << agreed << " agree");
  REQUIRE(checked >= min_fraction * (checked + skipped));
  if (min_fraction > 0) REQUIRE(checked > 0);
  REQUIRE(agreed >= min_agree * checked);
  return checked;
}

inline std::vector<std::size_t> sample_real(const Owned& a, std::size_t stride) {
  std::vector<std::size_t> out;
  std::size_t k = 0;
  a.for_each_real([&](std::size_t i) {
    if (k++ % stride == 0) out.push_back(i);
  });
  return out;
}

// Sanitizer builds run the numerics several times slower, so a long finite-difference sweep
// over a big tensor samples up to 4x sparser there, never below 40 samples (kinks skip many).
inline std::size_t sanitizer_stride(std::size_t numel, std::size_t stride) {
  return kSanitized ? std::max(stride, std::min(4 * stride, numel / 40)) : stride;
}

inline std::vector<std::size_t> sample_all(std::size_t n, std::size_t stride) {
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < n; i += stride) out.push_back(i);
  return out;
}

}  // namespace yelan::test
