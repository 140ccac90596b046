// Winograd F(4x4, 3x3) forward on native vectors: the transforms and the chunk loop, shared
// by the fp32 kernel (conv_simd.cpp, whose GEMMs are conv_direct.inl's register-blocked
// `tile`) and the bf16 one (conv_winograd_bf16.cpp, GEMMs on AVX512-BF16 pairs). Tiles are
// processed in chunks of kWinoChunk per thread: input transform -> 36 GEMMs -> output
// transform, all in a thread's scratch (thread_scratch) that stays in L2 and is allocated once
// per thread. Needs kernels/simd.h, kernels/parallel.h and kernels/conv.h.

constexpr int kWinoChunk = 48;
constexpr int kWinoNV = kBlock / VL;  // native vectors in a 16-channel block

// B^T d for six vectors (one column or row of a 6x6 tile). Grouped so that each product
// contracts into an FMA and rows 3 and 4 share their differences: 14 operations, not 18.
inline void wino_bt(const vf d[6], vf o[6]) {
  const vf four = vf{} + 4.f, five = vf{} + 5.f, two = vf{} + 2.f;
  const vf p = d[3] - d[1], q = d[4] - d[2];
  o[0] = four * d[0] + (d[4] - five * d[2]);
  o[1] = (d[3] + d[4]) - four * (d[1] + d[2]);
  o[2] = four * (d[1] - d[2]) + (d[4] - d[3]);
  o[3] = q + two * p;
  o[4] = q - two * p;
  o[5] = four * d[1] + (d[5] - five * d[3]);
}

// A^T m: six vectors to four.
inline void wino_at(const vf m[6], vf o[4]) {
  const vf a = m[1] + m[2], b = m[1] - m[2], c = m[3] + m[4], d = m[3] - m[4];
  o[0] = m[0] + a + c;
  o[1] = b + (vf{} + 2.f) * d;
  o[2] = a + (vf{} + 4.f) * c;
  o[3] = b + (vf{} + 8.f) * d + m[5];
}

// The layouts of one chunk: V[36][ICB][kWinoChunk][16] transformed inputs of element type T
// (stored by store_v(T* at, vf value), which may round), M[OCB][kWinoChunk][36][16] fp32
// products. gemm(V, M, tc) fills M's first tc tiles of every product and block. M keeps a
// tile's 36 products together: the output transform reads them as one 2.3 KB run the
// prefetcher follows (laid out by product, its 36 strided loads a tile waited on L2).
inline std::ptrdiff_t wino_v_index(int xi, int cb, int t, int icb) {
  return ((std::ptrdiff_t(xi) * icb + cb) * kWinoChunk + t) * kBlock;
}
constexpr std::ptrdiff_t kWinoMTile = 36 * kBlock;                  // M: to the next tile
constexpr std::ptrdiff_t kWinoMBlock = kWinoChunk * kWinoMTile;     // M: to the next output block
inline std::ptrdiff_t wino_m_index(int xi, int ob, int t) { return ob * kWinoMBlock + t * kWinoMTile + xi * kBlock; }

// The transforms' fixed-count loops are unrolled by pragma, not left to the optimiser's
// heuristics: kept as loops the 6x6 tiles live on the stack with an index multiply per
// access (at -O2 the transforms took half of a bf16 Winograd convolution on stage 1's
// shapes), and even -O3 kept the output transform's clipped row pass a loop (2.5 -> 2.2 ms
// of transforms on the eighteen shapes once it too unrolled).
template <class T, class StoreV, class Gemm>
void winograd_fwd(const ConvShape& s, const float* x, const float* bias, float* y, StoreV store_v, Gemm gemm) {
  const int OH = s.oh(), OW = s.ow(), ICB = s.icb(), OCB = s.ocb();
  const int TH = (OH + 3) / 4, TW = (OW + 3) / 4, T_ = TH * TW;
  const int chunks = (T_ + kWinoChunk - 1) / kWinoChunk;
  const std::ptrdiff_t x_plane = std::ptrdiff_t(s.ih) * s.iw * kBlock, y_plane = std::ptrdiff_t(OH) * OW * kBlock;
  const std::size_t cs = std::size_t(kWinoChunk) * kBlock;  // one channel block of one product
  on_team(worth_sharing(s.flops() / 4), [&] {  // a quarter of the multiplies
    // V's share is sized in floats whatever T is (bf16 uses half of it): one scratch shape.
    float* scratch = thread_scratch(std::size_t(36) * (ICB + OCB) * cs);
    T* V = reinterpret_cast<T*>(scratch);
    float* M = scratch + std::size_t(36) * ICB * cs;
#pragma omp for collapse(2) schedule(static)
    for (int n = 0; n < s.n; ++n)
      for (int ch = 0; ch < chunks; ++ch) {
        const int t0 = ch * kWinoChunk, tc = std::min(kWinoChunk, T_ - t0);
        // Input transform: V[xi][cb][t] = (B^T d B)[xi] for the tile's 6x6 input patch.
        for (int cb = 0; cb < ICB; ++cb) {
          const float* xb = x + (std::ptrdiff_t(n) * ICB + cb) * x_plane;
          for (int t = 0; t < tc; ++t) {
            const int ih0 = (t0 + t) / TW * 4 - s.pad_h, iw0 = (t0 + t) % TW * 4 - s.pad_w;
            // Most tiles lie inside the image: their 36 loads need no test.
            const bool inside = ih0 >= 0 && iw0 >= 0 && ih0 + 6 <= s.ih && iw0 + 6 <= s.iw;
#pragma GCC unroll 6
            for (int q = 0; q < kWinoNV; ++q) {
              vf d[6][6], r[6][6];
              if (inside) {
                const float* p = xb + (std::ptrdiff_t(ih0) * s.iw + iw0) * kBlock + q * VL;
#pragma GCC unroll 6
                for (int i = 0; i < 6; ++i)
#pragma GCC unroll 6
                  for (int j = 0; j < 6; ++j) d[i][j] = loadf(p + (std::ptrdiff_t(i) * s.iw + j) * kBlock);
              } else {
#pragma GCC unroll 6
                for (int i = 0; i < 6; ++i)
#pragma GCC unroll 6
                  for (int j = 0; j < 6; ++j) {
                    const int ih = ih0 + i, iw = iw0 + j;
                    d[i][j] = ih >= 0 && ih < s.ih && iw >= 0 && iw < s.iw
                                  ? loadf(xb + (std::ptrdiff_t(ih) * s.iw + iw) * kBlock + q * VL)
                                  : vf{};
                  }
              }
#pragma GCC unroll 6
              for (int j = 0; j < 6; ++j) {  // columns: r[.][j] = B^T d[.][j]
                vf col[6], out[6];
#pragma GCC unroll 6
                for (int i = 0; i < 6; ++i) col[i] = d[i][j];
                wino_bt(col, out);
#pragma GCC unroll 6
                for (int i = 0; i < 6; ++i) r[i][j] = out[i];
              }
#pragma GCC unroll 6
              for (int i = 0; i < 6; ++i) {  // rows: (B^T d) B
                vf out[6];
                wino_bt(r[i], out);
#pragma GCC unroll 6
                for (int j = 0; j < 6; ++j) store_v(V + wino_v_index(i * 6 + j, cb, t, ICB) + q * VL, out[j]);
              }
            }
          }
        }
        // 36 GEMMs: M[xi][ob][t] = sum over channels of V[xi][cb][t] U[xi][ob][cb].
        gemm(static_cast<const T*>(V), M, tc);
        // Output transform: y = A^T M A + bias, clipped at the image's right and bottom.
        for (int ob = 0; ob < OCB; ++ob) {
          float* yb = y + (std::ptrdiff_t(n) * OCB + ob) * y_plane;
          for (int t = 0; t < tc; ++t) {
            const int oh0 = (t0 + t) / TW * 4, ow0 = (t0 + t) % TW * 4;
#pragma GCC unroll 6
            for (int q = 0; q < kWinoNV; ++q) {
              const vf b = bias ? loadf(bias + ob * kBlock + q * VL) : vf{};
              vf r[4][6];
#pragma GCC unroll 6
              for (int j = 0; j < 6; ++j) {
                vf col[6], out[4];
#pragma GCC unroll 6
                for (int i = 0; i < 6; ++i) col[i] = loadf(M + wino_m_index(i * 6 + j, ob, t) + q * VL);
                // Every output of A^T m takes m[1] with coefficient 1, so the bias added at
                // m[1][1] reaches all 16 outputs: one addition instead of 16.
                if (j == 1) col[1] = col[1] + b;
                wino_at(col, out);
#pragma GCC unroll 4
                for (int i = 0; i < 4; ++i) r[i][j] = out[i];
              }
              // The clip is a predicate on each store, not a loop bound, so both passes
              // unroll (a bound the compiler cannot count kept A^T's row pass a loop).
              const int ni = std::min(4, OH - oh0), nj = std::min(4, OW - ow0);
              float* yt = yb + (std::ptrdiff_t(oh0) * OW + ow0) * kBlock + q * VL;
#pragma GCC unroll 4
              for (int i = 0; i < 4; ++i) {
                vf out[4];
                wino_at(r[i], out);
#pragma GCC unroll 4
                for (int j = 0; j < 4; ++j)
                  if (i < ni && j < nj) storef(yt + (std::ptrdiff_t(i) * OW + j) * kBlock, s.relu ? vmax(out[j], vf{}) : out[j]);
              }
            }
          }
        }
      }
  });
}
