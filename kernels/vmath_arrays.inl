// Array drivers of the vector math functions (after simd_types.inl and vmath_vec.inl).
// The tail goes through a zero-padded vector, so every element gets the same formula.
template <vf (*F)(vf)>
void apply(const float* x, float* y, std::size_t n) {
  std::size_t i = 0;
  for (; i + VL <= n; i += VL) storef(y + i, F(loadf(x + i)));
  if (i < n) {
    float in[VL] = {}, out[VL];
    for (std::size_t k = 0; i + k < n; ++k) in[k] = x[i + k];
    storef(out, F(loadf(in)));
    for (std::size_t k = 0; i + k < n; ++k) y[i + k] = out[k];
  }
}
