#include "layers/param.h"

#include <atomic>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <new>
#include <random>

namespace yelan::layers {

namespace {
std::atomic<std::size_t> g_live{0}, g_peak{0};
}  // namespace

std::size_t floats_live_bytes() { return g_live.load(); }
std::size_t floats_peak_bytes() { return g_peak.load(); }
void reset_floats_peak() { g_peak.store(g_live.load()); }

void Floats::Free::operator()(float* p) const {
  g_live.fetch_sub(bytes);
  std::free(p);
}

Floats::Floats(std::size_t n) : n_(n) {
  const std::size_t bytes = (std::max<std::size_t>(n, 1) * sizeof(float) + 63) / 64 * 64;
  float* mem = static_cast<float*>(std::aligned_alloc(64, bytes));
  if (!mem) throw std::bad_alloc();
  p_ = std::unique_ptr<float, Free>(mem, Free{bytes});
  const std::size_t now = g_live.fetch_add(bytes) + bytes;
  for (std::size_t peak = g_peak.load(); now > peak && !g_peak.compare_exchange_weak(peak, now);) {}
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

namespace {
thread_local bool g_grad_enabled = true;
}
bool grad_enabled() { return g_grad_enabled; }
NoGrad::NoGrad() : saved_(g_grad_enabled) { g_grad_enabled = false; }
NoGrad::~NoGrad() { g_grad_enabled = saved_; }

}  // namespace yelan::layers
