#include "layers/param.h"

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <new>
#include <random>

namespace yelan::layers {

void Floats::Free::operator()(float* p) const { std::free(p); }

Floats::Floats(std::size_t n) : n_(n) {
  const std::size_t bytes = (std::max<std::size_t>(n, 1) * sizeof(float) + 63) / 64 * 64;
  p_.reset(static_cast<float*>(std::aligned_alloc(64, bytes)));
  if (!p_) throw std::bad_alloc();
  zero();
}

void Floats::zero() {
  if (n_) std::memset(p_.get(), 0, n_ * sizeof(float));
}

Param::Param(std::string n, std::vector<std::int64_t> s, bool train) : name(std::move(n)), shape(std::move(s)), trainable(train) {
  std::size_t count = 1;
  for (auto d : shape) count *= std::size_t(d);
  value = Floats(count);
  grad = Floats(train ? count : 0);
}

void init_uniform_fan_in(Param& p, std::int64_t fan_in, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  const double bound = 1.0 / std::sqrt(double(fan_in));
  std::uniform_real_distribution<double> u(-bound, bound);
  for (std::size_t i = 0; i < p.numel(); ++i) p.value[i] = float(u(rng));
}

}  // namespace yelan::layers
