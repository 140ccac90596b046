// Counter-based randomness for the simulator. Every random draw is a pure function of
// (seed, stream, index), so results never depend on thread count or on the order in which
// pixels, rows or objects are visited: the same seed gives the same bytes everywhere.
#pragma once
#include <cmath>
#include <cstdint>

namespace yelan::camera::sim {

inline std::uint64_t mix64(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ull;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

inline std::uint64_t hash64(std::uint64_t seed, std::uint64_t stream, std::uint64_t index) {
  return mix64(mix64(mix64(seed) ^ stream) ^ index);
}

// Uniform in [0, 1) with 53 random bits.
inline double uniform01(std::uint64_t seed, std::uint64_t stream, std::uint64_t index) {
  return double(hash64(seed, stream, index) >> 11) * 0x1.0p-53;
}

// Standard normal by Box-Muller from two counter draws.
inline double normal01(std::uint64_t seed, std::uint64_t stream, std::uint64_t index) {
  double u1 = uniform01(seed, stream, 2 * index), u2 = uniform01(seed, stream, 2 * index + 1);
  if (u1 < 1e-300) u1 = 1e-300;
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
}

// A sequential generator for code that draws many values in a fixed order (character
// shapes, scene layout); seeded from a stream so different users never share draws.
class Rng {
 public:
  Rng(std::uint64_t seed, std::uint64_t stream) : seed_(seed), stream_(stream) {}
  double uniform() { return uniform01(seed_, stream_, n_++); }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  double normal() { return normal01(seed_, stream_ ^ 0x5bd1e995ull, n_++); }
  std::uint64_t bits() { return hash64(seed_, stream_, n_++); }
  int below(int n) { return int(uniform() * n) % n; }

 private:
  std::uint64_t seed_, stream_, n_ = 0;
};

}  // namespace yelan::camera::sim
