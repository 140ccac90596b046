// One benchmark measurement, as `yelan bench kernels --json` prints it.
#pragma once
#include <random>
#include <string>

#include "layers/param.h"

namespace yelan::bench {

struct Record {
  std::string where, op, algo = "direct";
  int kh, kw, stride, cin, cout, h, w;
  std::string isa;
  int threads;
  double ms, gflops, peak_gflops, pct_peak;
  double torch_gflops = 0;   // 0: not measured
  double onednn_gflops = 0;
  double bytes = 0;          // memory-bound ops: bytes read + written per call
  double memcpy_ms = 0;      // a memcpy of `bytes / 2` (read + write the same bytes)
};

// 64-byte aligned floats filled with uniform noise in [-1, 1].
struct Buffer {
  layers::Floats mem;
  float* p;
  explicit Buffer(std::size_t n, unsigned seed) : mem(n) {
    p = mem.data();
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(-1.f, 1.f);
    for (std::size_t i = 0; i < n; ++i) p[i] = u(rng);
  }
};

}  // namespace yelan::bench
