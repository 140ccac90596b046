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

// The layouts of one chunk: V[36][ICB][kWinoChunk][16] (+ kWinoVPad) transformed inputs of element type T
// (stored by store_v(T* at, vf value), which may round), M[OCB][kWinoChunk][36][16] fp32
// products. gemm(V, M, tc) fills M's first tc tiles of every product and block. M keeps a
// tile's 36 products together: the output transform reads them as one 2.3 KB run the
// prefetcher follows (laid out by product, its 36 strided loads a tile waited on L2).
// One product's share of V is padded by a cache line's kBlock elements: unpadded, the input
// transform's 36 stores of a vector lay a multiple of 3 KB apart, in 2 to 4 of L1's 64 sets
// (ICB 1 to 3 on fp32), and each could evict the last.
constexpr std::ptrdiff_t kWinoVPad = kBlock;
inline std::ptrdiff_t wino_v_product(int icb) { return std::ptrdiff_t(icb) * kWinoChunk * kBlock + kWinoVPad; }
inline std::ptrdiff_t wino_v_index(int xi, int cb, int t, int icb) {
  return xi * wino_v_product(icb) + (std::ptrdiff_t(cb) * kWinoChunk + t) * kBlock;
}
constexpr std::ptrdiff_t kWinoMTile = 36 * kBlock;                  // M: to the next tile
constexpr std::ptrdiff_t kWinoMBlock = kWinoChunk * kWinoMTile;     // M: to the next output block
inline std::ptrdiff_t wino_m_index(int xi, int ob, int t) { return ob * kWinoMBlock + t * kWinoMTile + xi * kBlock; }

// d = the 6x6 patch at (ih0, iw0) of one vector's plane (base: its pixel (0, 0), h x w pixels
// kBlock floats apart), zeros outside the plane. Most patches lie inside: 36 loads, no test.
inline void load_patch(vf d[6][6], const float* base, int h, int w, int ih0, int iw0) {
  if (ih0 >= 0 && iw0 >= 0 && ih0 + 6 <= h && iw0 + 6 <= w) {
    const float* p = base + (std::ptrdiff_t(ih0) * w + iw0) * kBlock;
#pragma GCC unroll 6
    for (int i = 0; i < 6; ++i)
#pragma GCC unroll 6
      for (int j = 0; j < 6; ++j) d[i][j] = loadf(p + (std::ptrdiff_t(i) * w + j) * kBlock);
    return;
  }
#pragma GCC unroll 6
  for (int i = 0; i < 6; ++i)
#pragma GCC unroll 6
    for (int j = 0; j < 6; ++j) {
      const int ih = ih0 + i, iw = iw0 + j;
      d[i][j] = ih >= 0 && ih < h && iw >= 0 && iw < w ? loadf(base + (std::ptrdiff_t(ih) * w + iw) * kBlock) : vf{};
    }
}

// The input of winograd_fwd: patch(d, n, cb, ih0, iw0, q) loads native vector q of channel
// block cb of image n. A plain map:
struct PlainInput {
  const float* x;
  int icb, h, w;
  void patch(vf d[6][6], int n, int cb, int ih0, int iw0, int q) const {
    const std::ptrdiff_t plane = std::ptrdiff_t(h) * w * kBlock;
    load_patch(d, x + (std::ptrdiff_t(n) * icb + cb) * plane + q * VL, h, w, ih0, iw0);
  }
};

// d = lanes from..from+7 of lo, then lanes 0-7 of hi (16-lane vectors; from is 0 or 8). A
// template on the lane count so that narrower ISAs, which never split a vector, compile none
// of it.
template <int L>
void join_halves(vf d[6][6], const vf lo[6][6], const vf hi[6][6], int from) {
  if constexpr (L == 16) {
    using V = std::conditional_t<L == 16, vf, vf>;  // dependent: checked only where instantiated
#pragma GCC unroll 6
    for (int i = 0; i < 6; ++i)
#pragma GCC unroll 6
      for (int j = 0; j < 6; ++j)
        d[i][j] = from == 0 ? __builtin_shufflevector(V(lo[i][j]), V(hi[i][j]), 0, 1, 2, 3, 4, 5, 6, 7, 16, 17, 18, 19, 20, 21, 22, 23)
                            : __builtin_shufflevector(V(lo[i][j]), V(hi[i][j]), 8, 9, 10, 11, 12, 13, 14, 15, 16, 17, 18, 19, 20, 21, 22, 23);
  }
}

// Two maps concatenated in channels, read in place (ConcatInput; one image): channels below
// a_c from a, the rest from b placed at (top, left). a_c % 8 == 0, so a native vector of 8 or
// fewer lanes comes whole from one map; a 16-lane one at a block of a_c % 16 == 8 (stage 1's
// 24 + 24) is two half vectors, joined by a shuffle.
struct CatInput {
  const ConcatInput& in;
  int h, w;  // the convolution's input size, a's
  void patch(vf d[6][6], int /*n*/, int cb, int ih0, int iw0, int q) const {
    const int c0 = cb * kBlock + q * VL;  // the vector's first channel
    if (c0 + VL <= in.a_c) return load_patch(d, lane(in.a, c0, h, w), h, w, ih0, iw0);
    // Below 16 lanes a vector never straddles the two (a_c % 8 == 0).
    if (VL < 16 || c0 >= in.a_c) return b_patch(d, c0 - in.a_c, ih0, iw0);
    if constexpr (VL == 16) {  // a's last block (its lanes from a_c % 16 up are padding) and b's first
      vf lo[6][6], hi[6][6];
      load_patch(lo, lane(in.a, c0, h, w), h, w, ih0, iw0);
      b_patch(hi, 0, ih0, iw0);
      join_halves<VL>(d, lo, hi, 0);
    }
  }
  // Where channel c's lane of pixel (0, 0) lies in a map of h x w.
  static const float* lane(const float* m, int c, int h, int w) {
    return m + (std::ptrdiff_t(c / kBlock) * h * w) * kBlock + c % kBlock;
  }
  // b's channels from c on, at the convolution's input coordinates.
  void b_patch(vf d[6][6], int c, int ih0, int iw0) const {
    const int bh = in.b_h, bw = in.b_w, bi = ih0 - in.top, bj = iw0 - in.left;
    if (VL < 16 || c % kBlock + VL <= kBlock) return load_patch(d, lane(in.b, c, bh, bw), bh, bw, bi, bj);
    if constexpr (VL == 16) {  // lanes 8-15 of one block of b, then lanes 0-7 of the next (or padding)
      vf lo[6][6], hi[6][6] = {};
      load_patch(lo, lane(in.b, c - 8, bh, bw), bh, bw, bi, bj);
      if (c + 8 < in.b_c) load_patch(hi, lane(in.b, c + 8, bh, bw), bh, bw, bi, bj);
      join_halves<VL>(d, lo, hi, 8);
    }
  }
};

// The transforms' fixed-count loops are unrolled by pragma, not left to the optimiser's
// heuristics: kept as loops the 6x6 tiles live on the stack with an index multiply per
// access (at -O2 the transforms took half of a bf16 Winograd convolution on stage 1's
// shapes), and even -O3 kept the output transform's clipped row pass a loop (2.5 -> 2.2 ms
// of transforms on the eighteen shapes once it too unrolled).
template <class T, class Input, class StoreV, class Gemm>
void winograd_fwd(const ConvShape& s, const Input& in, const float* bias, float* y, StoreV store_v, Gemm gemm) {
  const int OH = s.oh(), OW = s.ow(), ICB = s.icb(), OCB = s.ocb();
  const int TH = (OH + 3) / 4, TW = (OW + 3) / 4, T_ = TH * TW;
  const int chunks = (T_ + kWinoChunk - 1) / kWinoChunk;
  const std::ptrdiff_t y_plane = std::ptrdiff_t(OH) * OW * kBlock;
  const std::size_t cs = std::size_t(kWinoChunk) * kBlock;  // one channel block of one product
  on_team(worth_sharing(s.flops() / 4), [&] {  // a quarter of the multiplies
    // V's share is sized in floats whatever T is (bf16 uses half of it): one scratch shape.
    float* scratch = thread_scratch(std::size_t(36) * (wino_v_product(ICB) + OCB * cs));
    T* V = reinterpret_cast<T*>(scratch);
    float* M = scratch + std::size_t(36) * wino_v_product(ICB);
#pragma omp for collapse(2) schedule(static)
    for (int n = 0; n < s.n; ++n)
      for (int ch = 0; ch < chunks; ++ch) {
        const int t0 = ch * kWinoChunk, tc = std::min(kWinoChunk, T_ - t0);
        // Input transform: V[xi][cb][t] = (B^T d B)[xi] for the tile's 6x6 input patch.
        for (int cb = 0; cb < ICB; ++cb) {
          for (int t = 0; t < tc; ++t) {
            const int ih0 = (t0 + t) / TW * 4 - s.pad_h, iw0 = (t0 + t) % TW * 4 - s.pad_w;
#pragma GCC unroll 6
            for (int q = 0; q < kWinoNV; ++q) {
              vf d[6][6], r[6][6];
              in.patch(d, n, cb, ih0, iw0, q);
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
