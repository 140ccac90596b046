// Native-width vector types for kernels written once with GCC vector extensions and
// compiled per ISA. The including file defines SIMD_VL (floats per native vector: 16
// AVX-512, 8 AVX2, 4 NEON, 1 for plain scalar code) and includes this inside an anonymous
// namespace; -ffp-contract=fast makes `a * b + c` one FMA.

constexpr int VL = SIMD_VL;
typedef float vf __attribute__((vector_size(SIMD_VL * 4)));
typedef int vi __attribute__((vector_size(SIMD_VL * 4)));
// Memory goes through under-aligned aliases: buffers need only element alignment.
typedef float vfu __attribute__((vector_size(SIMD_VL * 4), aligned(4)));

inline vf loadf(const float* p) { return *reinterpret_cast<const vfu*>(p); }
inline void storef(float* p, vf v) { *reinterpret_cast<vfu*>(p) = v; }
inline vf splat(float s) { return vf{} + s; }
inline vf select(vi mask, vf a, vf b) { return (vf)((mask & (vi)a) | (~mask & (vi)b)); }
inline vf vmax(vf a, vf b) { return select(a > b, a, b); }
inline vf vmin(vf a, vf b) { return select(a < b, a, b); }
inline float hsum(vf v) {
  float s = 0;
  for (int i = 0; i < VL; ++i) s += v[i];
  return s;
}
