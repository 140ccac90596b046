// The register-blocked direct convolution of kernels/conv.h, over the vectors of
// kernels/simd.h; part of conv_simd.cpp, which sizes the tile to the ISA's register file
// (CONV_R pixels x CONV_NB 16-channel output blocks; CONV_DW_CT input lanes per
// backward-weights pass). A 16-channel block is CONV_NV = 16 / VL native vectors, so the
// compiler never sees a vector wider than the hardware's.

constexpr int CONV_NV = kBlock / VL;

struct Tap {
  std::ptrdiff_t src, w;  // offsets in floats from the tile's source and weight bases
};

struct TileArgs {
  const float* src;              // source pixel of tile column 0, channel block 0
  std::ptrdiff_t src_r, src_cb;  // step to the next tile column / next source channel block
  const float* w;                // weights of output block 0, source block 0
  std::ptrdiff_t w_cb, w_ob;     // step to the next source block / next output block
  const Tap* taps;
  int ntaps, ncb;
  int last_lanes = kBlock;       // source lanes of the last source block that are channels
                                 // (the rest are zero padding: skipped, not multiplied)
  float* dst;                    // destination pixel of tile column 0, output block 0
  std::ptrdiff_t dst_r, dst_ob;
  const float* bias;             // null, or 16 per output block
  bool relu = false;             // stores max(0, sum)
};

// A tile's last output block may hold at most 8 channels (kBlock / 2): the 24-channel
// layers of stage 1 (8 in their second block) and the pose net's 8-channel ones. Only its
// lower half is then computed, on vectors of 8 lanes (of 4 on NEON: never wider than the
// native ones), and the upper half stored as zeros. On AVX-512 the half is one 256-bit
// vector, which cores that split 512-bit FMAs in two (AMD Zen 4) run at twice the rate; on
// the others it skips the block's upper native vectors outright. Lanes past the channels
// hold zero weights and bias, so the stored zeros are what the full block would compute.
constexpr int HALF_VL = VL < kBlock / 2 ? VL : kBlock / 2;
constexpr int HALF_NV = kBlock / 2 / HALF_VL;
typedef float vhalf __attribute__((vector_size(HALF_VL * 4)));
typedef float vhalfu __attribute__((vector_size(HALF_VL * 4), aligned(4)));

// A tile needs 8 independent FMA chains to keep two FMA pipes of latency 4 busy. One with
// fewer accumulators (a row's border columns, one pixel each; the remainders of short rows;
// a 16-channel layer's 6 pixels) splits each into P partial sums over the source lanes, lane
// c into partial c % P, added in order at the end, as many as fit the register file less 4
// (weights, broadcast). A one-pixel tile was one chain, a quarter of the rate: on stage 2's
// 22-column maps its two border columns took 18% of a residual block's time.
constexpr int kFmaChains = 8;
constexpr int kVecRegs = VL == 8 ? 16 : 32;  // AVX2 16 ymm; AVX-512 32 zmm; NEON 32 q

constexpr int partial_sums(int chains) {
  const int want = chains >= kFmaChains ? 1 : (kFmaChains + chains - 1) / chains;
  const int fit = (kVecRegs - 4) / chains;
  return want < fit ? want : fit < 1 ? 1 : fit;
}

// R output pixels x NB output blocks, the last of them half when HALF: NQ full native
// vectors and NH half ones per pixel.
template <int R, int NB, bool HALF = false>
void tile(const TileArgs& a) {
  constexpr int NF = HALF ? NB - 1 : NB;  // full blocks
  constexpr int NQ = NF * CONV_NV;
  constexpr int NH = HALF ? HALF_NV : 0;
  constexpr int CHAINS = R * (NQ + NH);
  constexpr int P = partial_sums(CHAINS);
  vf acc[P][R][NQ > 0 ? NQ : 1];
  vhalf hacc[P][R][NH > 0 ? NH : 1];
  const float* hb = a.bias ? a.bias + NF * kBlock : nullptr;
#pragma GCC unroll 16
  for (int p = 0; p < P; ++p)
#pragma GCC unroll 16
    for (int r = 0; r < R; ++r) {
#pragma GCC unroll 16
      for (int q = 0; q < NQ; ++q)
        acc[p][r][q] = a.bias && p == 0 ? loadf(a.bias + (q / CONV_NV) * kBlock + (q % CONV_NV) * VL) : vf{};
#pragma GCC unroll 16
      for (int q = 0; q < NH; ++q) hacc[p][r][q] = hb && p == 0 ? *reinterpret_cast<const vhalfu*>(hb + q * HALF_VL) : vhalf{};
    }
  // Source lane c of one tap into partial p: R broadcasts times NQ + NH weight vectors.
  const auto lane = [&](const float* st, const float* wt, int c, int p) __attribute__((always_inline)) {
    vf wv[NQ > 0 ? NQ : 1];
    vhalf hv[NH > 0 ? NH : 1];
#pragma GCC unroll 16
    for (int q = 0; q < NQ; ++q) wv[q] = loadf(wt + (q / CONV_NV) * a.w_ob + c * kBlock + (q % CONV_NV) * VL);
#pragma GCC unroll 16
    for (int q = 0; q < NH; ++q) hv[q] = *reinterpret_cast<const vhalfu*>(wt + NF * a.w_ob + c * kBlock + q * HALF_VL);
#pragma GCC unroll 16
    for (int r = 0; r < R; ++r) {
      const float xv = st[r * a.src_r + c];
#pragma GCC unroll 16
      for (int q = 0; q < NQ; ++q) acc[p][r][q] += xv * wv[q];
#pragma GCC unroll 16
      for (int q = 0; q < NH; ++q) hacc[p][r][q] += xv * hv[q];
    }
  };
  for (int cb = 0; cb < a.ncb; ++cb) {
    const int lanes = cb == a.ncb - 1 ? a.last_lanes : kBlock;
    const float* s = a.src + cb * a.src_cb;
    const float* w = a.w + cb * a.w_cb;
    for (int t = 0; t < a.ntaps; ++t) {
      const float* st = s + a.taps[t].src;
      const float* wt = w + a.taps[t].w;
      if (lanes == kBlock) {
#pragma GCC unroll 16
        for (int c = 0; c < kBlock; ++c) lane(st, wt, c, c % P);
      } else if (lanes == kBlock / 2) {  // 8-channel maps and 24-channel ones' last block:
        // unrolled as the full block is (the counted loop below spent more instructions on
        // addresses than on FMAs: half the FMA rate on AVX2). The same partials in the same order.
#pragma GCC unroll 8
        for (int c = 0; c < kBlock / 2; ++c) lane(st, wt, c, c % P);
      } else {
        int c = 0;
        for (; c + P <= lanes; c += P) {
#pragma GCC unroll 16
          for (int p = 0; p < P; ++p) lane(st, wt, c + p, p);
        }
#pragma GCC unroll 16
        for (int p = 0; p < P; ++p)
          if (c + p < lanes) lane(st, wt, c + p, p);
      }
    }
  }
#pragma GCC unroll 16
  for (int p = 1; p < P; ++p)
#pragma GCC unroll 16
    for (int r = 0; r < R; ++r) {
#pragma GCC unroll 16
      for (int q = 0; q < NQ; ++q) acc[0][r][q] += acc[p][r][q];
#pragma GCC unroll 16
      for (int q = 0; q < NH; ++q) hacc[0][r][q] += hacc[p][r][q];
    }
  if (a.relu) {
#pragma GCC unroll 16
    for (int r = 0; r < R; ++r) {
#pragma GCC unroll 16
      for (int q = 0; q < NQ; ++q) acc[0][r][q] = vmax(acc[0][r][q], vf{});
#pragma GCC unroll 16
      for (int q = 0; q < NH; ++q) hacc[0][r][q] = hacc[0][r][q] > vhalf{} ? hacc[0][r][q] : vhalf{};
    }
  }
#pragma GCC unroll 16
  for (int r = 0; r < R; ++r) {
#pragma GCC unroll 16
    for (int q = 0; q < NQ; ++q) storef(a.dst + r * a.dst_r + (q / CONV_NV) * a.dst_ob + (q % CONV_NV) * VL, acc[0][r][q]);
    float* d = a.dst + r * a.dst_r + NF * a.dst_ob;
#pragma GCC unroll 16
    for (int q = 0; q < NH; ++q) {
      *reinterpret_cast<vhalfu*>(d + q * HALF_VL) = hacc[0][r][q];
      *reinterpret_cast<vhalfu*>(d + kBlock / 2 + q * HALF_VL) = vhalf{};
    }
  }
}

// A tile of one half block only has twice CONV_R pixels: 12 independent FMA chains, as the
// FMA latency needs (6 ymm chains leave Zen 4's two 256-bit pipes a quarter idle); AVX2 12
// of 16 ymm, NEON 24 of 32 q. Tiles with full blocks beside the half keep CONV_R pixels.
constexpr int HALF_R = 2 * CONV_R;

using TileFn = void (*)(const TileArgs&);

template <int NB, bool HALF, int... R>
constexpr auto tiles_for(std::integer_sequence<int, R...>) {
  return std::array<TileFn, sizeof...(R)>{&tile<R + 1, NB, HALF>...};
}
template <bool HALF, int... NB>
constexpr auto tile_table(std::integer_sequence<int, NB...>) {
  return std::array<std::array<TileFn, CONV_R>, sizeof...(NB)>{
      tiles_for<NB + 1, HALF>(std::make_integer_sequence<int, CONV_R>{})...};
}
// kTiles[nb - 1][r - 1] is tile<r, nb>; kHalfLastTiles[nb - 1][r - 1] is tile<r, nb, true>
// (its [0] row unused: one half block alone takes kHalfTiles' longer rows).
constexpr auto kTiles = tile_table<false>(std::make_integer_sequence<int, CONV_NB>{});
constexpr auto kHalfLastTiles = tile_table<true>(std::make_integer_sequence<int, CONV_NB>{});
// kHalfTiles[r - 1] is tile<r, 1, true>, up to HALF_R pixels.
constexpr auto kHalfTiles = tiles_for<1, true>(std::make_integer_sequence<int, HALF_R>{});

// A half block alone on AVX2 (8 output channels, one ymm a pixel): the tile above broadcasts
// one source value per FMA, and AVX2 cores run broadcasts and FMAs at one rate, so it held half
// the FMA peak. Where a kernel row's three column taps read three neighbouring source pixels
// (stride 1, 3-wide kernels: stage 2's 8-channel layers), one broadcast of a source pixel
// feeds the three outputs that read it, each with its own tap's weights: R outputs take R + 2
// broadcasts and 3R FMAs per source lane and kernel row. Sums run per kernel row and lane
// over the three taps, not tap by tap as the tile's: the same terms in another order.
constexpr int ROW3_R = VL == 8 ? 10 : 0;  // 10 accumulators + 3 weights + 1 broadcast of 16 ymm
constexpr int ROW3_TILE = ROW3_R > 0 ? ROW3_R : 1;  // what the other ISAs compile and never call

struct Row3Args {
  TileArgs a;                      // src: output column 0's tap-0 source pixel; taps unused
  int nrow = 0;
  std::ptrdiff_t row_src[kMaxKernel], row_w[kMaxKernel];
  std::ptrdiff_t w_k = 0;          // weights: to the next column tap
};

template <int R>
void half_row3(const Row3Args& g) {
  const TileArgs& a = g.a;
  vhalf acc[R];
#pragma GCC unroll 16
  for (int r = 0; r < R; ++r) acc[r] = a.bias ? *reinterpret_cast<const vhalfu*>(a.bias) : vhalf{};
  // Source pixel p of lane c into the outputs that read it: output p - k at column tap k.
  const auto lane = [&](const float* s, const float* w, int c) __attribute__((always_inline)) {
    const vhalf w0 = *reinterpret_cast<const vhalfu*>(w + c * kBlock);
    const vhalf w1 = *reinterpret_cast<const vhalfu*>(w + g.w_k + c * kBlock);
    const vhalf w2 = *reinterpret_cast<const vhalfu*>(w + 2 * g.w_k + c * kBlock);
#pragma GCC unroll 16
    for (int p = 0; p < R + 2; ++p) {
      const float xv = s[p * a.src_r + c];
      if (p < R) acc[p] += xv * w0;
      if (p >= 1 && p - 1 < R) acc[p - 1] += xv * w1;
      if (p >= 2) acc[p - 2] += xv * w2;
    }
  };
  for (int cb = 0; cb < a.ncb; ++cb) {
    const int lanes = cb == a.ncb - 1 ? a.last_lanes : kBlock;
    for (int i = 0; i < g.nrow; ++i) {
      const float* s = a.src + cb * a.src_cb + g.row_src[i];
      const float* w = a.w + cb * a.w_cb + g.row_w[i];
      if (lanes == kBlock) {
#pragma GCC unroll 16
        for (int c = 0; c < kBlock; ++c) lane(s, w, c);
      } else if (lanes == kBlock / 2) {
#pragma GCC unroll 8
        for (int c = 0; c < kBlock / 2; ++c) lane(s, w, c);
      } else {
        for (int c = 0; c < lanes; ++c) lane(s, w, c);
      }
    }
  }
#pragma GCC unroll 16
  for (int r = 0; r < R; ++r) {
    if (a.relu) acc[r] = acc[r] > vhalf{} ? acc[r] : vhalf{};
    float* d = a.dst + r * a.dst_r;
    *reinterpret_cast<vhalfu*>(d) = acc[r];
    *reinterpret_cast<vhalfu*>(d + kBlock / 2) = vhalf{};
  }
}

// The tiles for a group of nb output blocks, the last of them half when half_last, and
// their widest tile in pixels.
inline const TileFn* tiles_for_group(int nb, bool half_last, int* tile_r) {
  *tile_r = half_last && nb == 1 ? HALF_R : CONV_R;
  if (!half_last) return kTiles[nb - 1].data();
  return nb == 1 ? kHalfTiles.data() : kHalfLastTiles[std::clamp(nb, 1, CONV_NB) - 1].data();
}

inline int floor_div(int a, int b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }
inline int ceil_div(int a, int b) { return -floor_div(-a, b); }

constexpr int kMaxTaps = kMaxKernel * kMaxKernel;

// One destination row of T columns. Destination column t reads source column
// base[k] + t * mult for column tap k (mult = stride for forward, 1 for a backward-data
// phase). Columns where every tap stays inside the source go in R-wide tiles sharing one
// tap list; the border columns go one by one with only their valid taps, so the source is
// never padded or copied.
struct RowJob {
  int T = 0, src_w = 0, mult = 1;
  int nrow = 0, ncol = 0;
  std::ptrdiff_t row_src[kMaxKernel], row_w[kMaxKernel];  // per row tap
  int col_base[kMaxKernel];                               // per column tap
  std::ptrdiff_t col_w[kMaxKernel];
};

// half_last: the tiles' last output block has at most 8 channels (see tile).
inline void run_row(const RowJob& job, TileArgs a, int nb, bool half_last = false) {
  int tile_r;
  const TileFn* tiles = tiles_for_group(nb, half_last, &tile_r);
  Tap taps[kMaxTaps];
  int t_lo = 0, t_hi = job.T;
  for (int k = 0; k < job.ncol; ++k) {
    t_lo = std::max(t_lo, ceil_div(-job.col_base[k], job.mult));
    t_hi = std::min(t_hi, floor_div(job.src_w - 1 - job.col_base[k], job.mult) + 1);
  }
  t_lo = std::min(t_lo, job.T);
  t_hi = std::max(t_hi, t_lo);
  int nt = 0;
  for (int i = 0; i < job.nrow; ++i)
    for (int k = 0; k < job.ncol; ++k)
      taps[nt++] = {job.row_src[i] + std::ptrdiff_t(job.col_base[k]) * kBlock, job.row_w[i] + job.col_w[k]};
  const float* src0 = a.src;
  float* dst0 = a.dst;
  a.src_r = std::ptrdiff_t(job.mult) * kBlock;
  a.taps = taps;
  a.ntaps = nt;
  int t_tiles = t_lo;  // the interior columns from here on go in tiles
  if constexpr (ROW3_R > 0) {
    if (nb == 1 && half_last && job.mult == 1 && job.ncol == 3 && job.col_base[1] == job.col_base[0] + 1 &&
        job.col_base[2] == job.col_base[0] + 2 && job.col_w[2] - job.col_w[1] == job.col_w[1] - job.col_w[0]) {
      Row3Args g;
      g.a = a;
      g.nrow = job.nrow;
      for (int i = 0; i < job.nrow; ++i) {
        g.row_src[i] = job.row_src[i] + std::ptrdiff_t(job.col_base[0]) * kBlock;
        g.row_w[i] = job.row_w[i] + job.col_w[0];
      }
      g.w_k = job.col_w[1] - job.col_w[0];
      for (; t_tiles + ROW3_R <= t_hi; t_tiles += ROW3_R) {
        g.a.src = src0 + t_tiles * a.src_r;
        g.a.dst = dst0 + t_tiles * a.dst_r;
        half_row3<ROW3_TILE>(g);
      }
    }
  }
  for (int t = t_tiles; t < t_hi; t += tile_r) {
    const int r = std::min(tile_r, t_hi - t);
    a.src = src0 + t * a.src_r;
    a.dst = dst0 + t * a.dst_r;
    tiles[r - 1](a);
  }
  for (int t = 0; t < job.T; ++t) {
    if (t >= t_lo && t < t_hi) continue;
    int ne = 0;
    for (int i = 0; i < job.nrow; ++i)
      for (int k = 0; k < job.ncol; ++k) {
        const int c = job.col_base[k] + t * job.mult;
        if (c < 0 || c >= job.src_w) continue;
        taps[ne++] = {job.row_src[i] + std::ptrdiff_t(job.col_base[k]) * kBlock, job.row_w[i] + job.col_w[k]};
      }
    a.taps = taps;
    a.ntaps = ne;
    a.src = src0 + t * a.src_r;
    a.dst = dst0 + t * a.dst_r;
    tiles[0](a);
  }
}

void conv_fwd(const ConvShape& s, const float* x, const float* w, const float* bias, float* y) {
  const int OH = s.oh(), OW = s.ow(), ICB = s.icb(), OCB = s.ocb();
  const std::ptrdiff_t x_plane = std::ptrdiff_t(s.ih) * s.iw * kBlock;
  const std::ptrdiff_t y_plane = std::ptrdiff_t(OH) * OW * kBlock;
  const std::ptrdiff_t w_tap = kBlock * kBlock, w_cb = std::ptrdiff_t(s.kh) * s.kw * w_tap;
  const std::ptrdiff_t w_ob = ICB * w_cb;
  const int groups = (OCB + CONV_NB - 1) / CONV_NB;
  on_team(worth_sharing(s.flops()), [&] {
#pragma omp for collapse(3) schedule(static)
    for (int n = 0; n < s.n; ++n)
      for (int g = 0; g < groups; ++g)
        for (int oh = 0; oh < OH; ++oh) {
          const int ob0 = g * CONV_NB, nb = std::min(CONV_NB, OCB - ob0);
          RowJob job;
          job.T = OW;
          job.src_w = s.iw;
          job.mult = s.stride;
          for (int kh = 0; kh < s.kh; ++kh) {
            const int ih = oh * s.stride - s.pad_h + kh;
            if (ih < 0 || ih >= s.ih) continue;
            job.row_src[job.nrow] = std::ptrdiff_t(ih) * s.iw * kBlock;
            job.row_w[job.nrow++] = kh * s.kw * w_tap;
          }
          job.ncol = s.kw;
          for (int kw = 0; kw < s.kw; ++kw) {
            job.col_base[kw] = kw - s.pad_w;
            job.col_w[kw] = kw * w_tap;
          }
          TileArgs a;
          a.src = x + std::ptrdiff_t(n) * ICB * x_plane;
          a.src_cb = x_plane;
          a.w = w + ob0 * w_ob;
          a.w_cb = w_cb;
          a.w_ob = w_ob;
          a.ncb = ICB;
          a.last_lanes = s.ic - (ICB - 1) * kBlock;
          a.dst = y + (std::ptrdiff_t(n) * OCB + ob0) * y_plane + std::ptrdiff_t(oh) * OW * kBlock;
          a.dst_r = kBlock;
          a.dst_ob = y_plane;
          a.bias = bias ? bias + ob0 * kBlock : nullptr;
          a.relu = s.relu;
          run_row(job, a, nb, ob0 + nb == OCB && s.oc - (OCB - 1) * kBlock <= kBlock / 2);
        }
  });
}

// dx[ih][iw] gathers dy[oh][ow] through tap (kh, kw) when ih = oh*s - pad_h + kh, likewise
// for columns. For a fixed destination row and column phase (iw % s) the valid taps are
// fixed and ow steps by 1 as iw steps by s: a stride-1 tile over dy writing every s-th dx.
void conv_bwd_data(const ConvShape& s, const float* dy, const float* w, const float* bias, float* dx) {
  const int OH = s.oh(), OW = s.ow(), ICB = s.icb(), OCB = s.ocb(), st = s.stride;
  const std::ptrdiff_t x_plane = std::ptrdiff_t(s.ih) * s.iw * kBlock;
  const std::ptrdiff_t y_plane = std::ptrdiff_t(OH) * OW * kBlock;
  const std::ptrdiff_t w_tap = kBlock * kBlock, w_cb = std::ptrdiff_t(s.kh) * s.kw * w_tap;
  const std::ptrdiff_t w_ob = OCB * w_cb;  // bwd layout: [ICB][OCB][KH][KW][16 oc][16 ic]
  const int groups = (ICB + CONV_NB - 1) / CONV_NB;
  on_team(worth_sharing(s.flops()), [&] {  // also a transposed convolution's forward
#pragma omp for collapse(3) schedule(static)
    for (int n = 0; n < s.n; ++n)
      for (int g = 0; g < groups; ++g)
        for (int ih = 0; ih < s.ih; ++ih) {
          const int cb0 = g * CONV_NB, nb = std::min(CONV_NB, ICB - cb0);
          RowJob base;
          base.src_w = OW;
          base.mult = 1;
          for (int kh = 0; kh < s.kh; ++kh) {
            const int num = ih + s.pad_h - kh;
            if (num < 0 || num % st != 0 || num / st >= OH) continue;
            base.row_src[base.nrow] = std::ptrdiff_t(num / st) * OW * kBlock;
            base.row_w[base.nrow++] = kh * s.kw * w_tap;
          }
          TileArgs a;
          a.src_cb = y_plane;
          a.w = w + cb0 * w_ob;
          a.w_cb = w_cb;
          a.w_ob = w_ob;
          a.ncb = OCB;
          a.last_lanes = s.oc - (OCB - 1) * kBlock;
          a.dst_r = std::ptrdiff_t(st) * kBlock;
          a.dst_ob = x_plane;
          a.bias = bias ? bias + cb0 * kBlock : nullptr;  // a transposed convolution's
          for (int phase = 0; phase < st && phase < s.iw; ++phase) {
            RowJob job = base;
            job.T = (s.iw - phase + st - 1) / st;
            for (int kw = 0; kw < s.kw; ++kw) {
              const int num = phase + s.pad_w - kw;  // ow = num / st + t when num % st == 0
              if (((num % st) + st) % st != 0) continue;
              job.col_base[job.ncol] = floor_div(num, st);
              job.col_w[job.ncol++] = kw * w_tap;
            }
            if (job.nrow == 0) job.ncol = 0;
            a.src = dy + std::ptrdiff_t(n) * OCB * y_plane;
            a.dst = dx + (std::ptrdiff_t(n) * ICB + cb0) * x_plane + (std::ptrdiff_t(ih) * s.iw + phase) * kBlock;
            run_row(job, a, nb, cb0 + nb == ICB && s.ic - (ICB - 1) * kBlock <= kBlock / 2);
          }
        }
  });
}

// dw[ob][cb][kh][kw][ci][:] = sum over n, oh, ow of x[n][cb][ih][iw][ci] * dy[n][ob][oh][ow][:].
// One row of dy against one row of x for one tap and CT input lanes; the accumulators live
// in dw between rows, so each sum still runs over (n, oh, ow) in order, bit for bit.
template <int CT>
void dw_row(const float* g, const float* xr, int ow_lo, int ow_hi, int st, int x_off, float* out) {
  vf acc[CT][CONV_NV];
#pragma GCC unroll 16
  for (int c = 0; c < CT; ++c)
#pragma GCC unroll 4
    for (int q = 0; q < CONV_NV; ++q) acc[c][q] = loadf(out + c * kBlock + q * VL);
  for (int ow = ow_lo; ow < ow_hi; ++ow) {
    vf d[CONV_NV];
#pragma GCC unroll 4
    for (int q = 0; q < CONV_NV; ++q) d[q] = loadf(g + std::ptrdiff_t(ow) * kBlock + q * VL);
    const float* xp = xr + std::ptrdiff_t(ow * st + x_off) * kBlock;
#pragma GCC unroll 16
    for (int c = 0; c < CT; ++c)
#pragma GCC unroll 4
      for (int q = 0; q < CONV_NV; ++q) acc[c][q] += xp[c] * d[q];
  }
#pragma GCC unroll 16
  for (int c = 0; c < CT; ++c)
#pragma GCC unroll 4
    for (int q = 0; q < CONV_NV; ++q) storef(out + c * kBlock + q * VL, acc[c][q]);
}

// One task per (ob, cb, kh): tasks never share output, so no reduction between threads. A
// task walks dy once, using each row for every kw and every CT-lane group while it is in L1:
// a pass over the whole batch per (tap, lane group) streamed the training stem's 23 MB dy
// 196 times a step on AVX2. Input lanes past s.ic are zero padding; their dw stays zero.
void conv_bwd_weights(const ConvShape& s, const float* x, const float* dy, float* dw, float* dbias) {
  const int ICB = s.icb(), OCB = s.ocb(), K = s.kh * s.kw, OH = s.oh(), OW = s.ow(), st = s.stride;
  const std::ptrdiff_t x_plane = std::ptrdiff_t(s.ih) * s.iw * kBlock;
  const std::ptrdiff_t y_plane = std::ptrdiff_t(OH) * OW * kBlock;
  const std::ptrdiff_t w_tap = kBlock * kBlock;
  on_team([&] {
#pragma omp for collapse(3) schedule(dynamic)
    for (int ob = 0; ob < OCB; ++ob)
      for (int cb = 0; cb < ICB; ++cb)
        for (int kh = 0; kh < s.kh; ++kh) {
          float* out = dw + ((std::ptrdiff_t(ob) * ICB + cb) * K + kh * s.kw) * w_tap;
          std::fill(out, out + s.kw * w_tap, 0.f);
          const int lanes = std::min(kBlock, s.ic - cb * kBlock);
          for (int n = 0; n < s.n; ++n)
            for (int oh = 0; oh < OH; ++oh) {
              const int ih = oh * st - s.pad_h + kh;
              if (ih < 0 || ih >= s.ih) continue;
              const float* g = dy + (std::ptrdiff_t(n) * OCB + ob) * y_plane + std::ptrdiff_t(oh) * OW * kBlock;
              const float* xr = x + (std::ptrdiff_t(n) * ICB + cb) * x_plane + std::ptrdiff_t(ih) * s.iw * kBlock;
              for (int kw = 0; kw < s.kw; ++kw) {
                const int ow_lo = std::max(0, ceil_div(s.pad_w - kw, st));
                const int ow_hi = std::min(OW, floor_div(s.iw - 1 + s.pad_w - kw, st) + 1);
                for (int c0 = 0; c0 < lanes; c0 += CONV_DW_CT)
                  dw_row<CONV_DW_CT>(g, xr + c0, ow_lo, ow_hi, st, kw - s.pad_w, out + kw * w_tap + c0 * kBlock);
              }
            }
        }
    if (dbias) {
#pragma omp for schedule(static)
      for (int ob = 0; ob < OCB; ++ob) {
        // float sums over 256 pixels at a time, added up in double: a bias sees every
        // pixel of the batch, far too many terms for one float accumulator
        double total[kBlock] = {};
        for (int n = 0; n < s.n; ++n) {
          const float* g = dy + (std::ptrdiff_t(n) * OCB + ob) * y_plane;
          for (std::ptrdiff_t p0 = 0; p0 < y_plane; p0 += 256 * kBlock) {
            vf acc[CONV_NV] = {};
            for (std::ptrdiff_t p = p0; p < std::min(y_plane, p0 + 256 * kBlock); p += kBlock)
              for (int q = 0; q < CONV_NV; ++q) acc[q] += loadf(g + p + q * VL);
            for (int q = 0; q < CONV_NV; ++q)
              for (int l = 0; l < VL; ++l) total[q * VL + l] += acc[q][l];
          }
        }
        for (int l = 0; l < kBlock; ++l) dbias[ob * kBlock + l] = float(total[l]);
      }
    }
  });
}
