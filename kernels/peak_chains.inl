// The FMA-throughput loop, compiled per ISA with PEAK_CHAINS independent accumulators of
// PEAK_LANES floats (enough chains to hide FMA latency on every FMA pipe).
typedef float vpk __attribute__((vector_size(PEAK_LANES * 4)));

float fma_loop(std::int64_t iterations, float seed) {
  vpk a[PEAK_CHAINS];
  const vpk m = vpk{} + 0.9999999f, c = vpk{} + 1e-7f;
  for (int i = 0; i < PEAK_CHAINS; ++i) a[i] = vpk{} + (seed + float(i));
  for (std::int64_t k = 0; k < iterations; ++k) {
#pragma GCC unroll 32
    for (int i = 0; i < PEAK_CHAINS; ++i) a[i] = a[i] * m + c;
  }
  float s = 0;
  for (int i = 0; i < PEAK_CHAINS; ++i)
    for (int l = 0; l < PEAK_LANES; ++l) s += a[i][l];
  return s;
}
