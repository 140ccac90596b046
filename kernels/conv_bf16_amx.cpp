// The AMX tile loop of conv_fwd_bf16_amx (conv_bf16.h says the algorithm). Compiled with
// AMX and AVX512-BF16 flags and called only where amx_bf16_available() holds; like an ISA
// variant file it uses no STL containers or inline templates a baseline file could share.
#include <immintrin.h>
#include <omp.h>

#include <cstddef>
#include <cstdint>

#include "kernels/conv_bf16.h"
#include "kernels/parallel.h"

namespace yelan::kernels {
namespace {

struct alignas(64) TileConfig {
  std::uint8_t palette = 1, start_row = 0, reserved[14] = {};
  std::uint16_t colsb[16] = {};
  std::uint8_t rows[16] = {};
};

// Tiles 0-3: accumulators (rows r0.. and r0+16.., blocks ob and ob+1); 4, 5: inputs; 6, 7: weights.
void configure_tiles() {
  TileConfig c;
  for (int t = 0; t < 8; ++t) {
    c.colsb[t] = 64;
    c.rows[t] = 16;
  }
  _tile_loadconfig(&c);
}

struct Plane {
  const std::uint16_t* x;  // [N][ICP][rows][32] bf16, padded
  std::ptrdiff_t rows, wp;
};

// Accumulates 32 output rows from r0 x NN blocks of 16 outputs from ob over every input pair and tap.
template <int NN>
void accumulate(const Plane& p, const std::uint16_t* w, int icp_n, int kh, int kw, std::ptrdiff_t r0) {
  _tile_zero(0);
  _tile_zero(1);
  _tile_zero(2);
  _tile_zero(3);
  const std::ptrdiff_t w_ob = std::ptrdiff_t(icp_n) * kh * kw * 512;
  for (int ip = 0; ip < icp_n; ++ip) {
    const std::uint16_t* xp = p.x + ip * p.rows * 32;
    for (int i = 0; i < kh; ++i)
      for (int j = 0; j < kw; ++j) {
        const std::uint16_t* a = xp + (r0 + i * p.wp + j) * 32;
        const std::uint16_t* b = w + ((std::ptrdiff_t(ip) * kh + i) * kw + j) * 512;
        _tile_loadd(4, a, 64);
        _tile_loadd(5, a + 16 * 32, 64);
        _tile_loadd(6, b, 64);
        _tile_dpbf16ps(0, 4, 6);
        _tile_dpbf16ps(2, 5, 6);
        if constexpr (NN == 2) {
          _tile_loadd(7, b + w_ob, 64);
          _tile_dpbf16ps(1, 4, 7);
          _tile_dpbf16ps(3, 5, 7);
        }
      }
  }
}

// Where the rows of a task go: a convolution's row f is output pixel (f / wp, f % wp), kept
// where f % wp < OW; a 2x2/2 transposed convolution's is input pixel (f / iw, f % iw), and its
// accumulator block nb = phase * OCB + ob lands on output pixel (2h + phase / 2, 2w + phase % 2).
struct Out {
  float* y;             // this image's output, [OCB][OH][OW][16]
  const float* bias;    // OCB * 16 or null
  int OH, OW, OCB;
  std::ptrdiff_t wp;    // row pitch of the task rows
  int up;               // 1: convolution; 2: 2x2/2 transposed convolution
  bool relu;
};

// The rows of one accumulator tile (16 rows from r0, block nb), plus bias, ReLU if asked.
void store_rows(const Out& o, const float* c, std::ptrdiff_t r0, int nb) {
  const int ob = nb % o.OCB, phase = nb / o.OCB;
  const __m512 b = o.bias ? _mm512_loadu_ps(o.bias + ob * kBlock) : _mm512_setzero_ps();
  float* yb = o.y + std::ptrdiff_t(ob) * o.OH * o.OW * kBlock;
  const int rows_in = o.up == 1 ? o.OH : o.OH / 2, cols_in = o.up == 1 ? o.OW : o.OW / 2;
  std::ptrdiff_t h = r0 / o.wp, w = r0 % o.wp;  // of row r, stepped (a division per row cost a third of a small task)
  for (int r = 0; r < 16 && h < rows_in; ++r) {
    if (w < cols_in) {
      __m512 v = _mm512_add_ps(_mm512_load_ps(c + r * 16), b);
      if (o.relu) v = _mm512_max_ps(v, _mm512_setzero_ps());
      const std::ptrdiff_t oh = o.up * h + phase / 2, ow = o.up * w + phase % 2;
      _mm512_storeu_ps(yb + (oh * o.OW + ow) * kBlock, v);
    }
    if (++w == o.wp) w = 0, ++h;
  }
}

// The convolution's input: one map (a, a_c = s.ic), or two concatenated in channels and read
// in place (conv_fwd_bf16_amx_cat: b after a's a_c channels, at (top, left), zeros around it).
struct Source {
  const float* a;
  int a_c;
  const float* b = nullptr;
  int b_c = 0, b_h = 0, b_w = 0, top = 0, left = 0;
};

// Where one input block's 16 channels come from along one input line: a row of a; a row of
// b (b0); a's low 8 channels then b0's low 8 (a_c % 16 == 8: the block where the maps meet);
// b0's high 8 then b1's low 8 (b's blocks seen 8 channels on); or zeros. A null b row: b's
// zeros (the line lies outside b, or the block past b's last).
enum class From : std::uint8_t { zeros, a, b, a_b_halves, b_halves };
struct BlockLine {
  From from = From::zeros;
  const float *a = nullptr, *b0 = nullptr, *b1 = nullptr;
};

BlockLine block_line(const ConvShape& s, const Source& x, int n, int cb, std::ptrdiff_t h) {
  BlockLine l;
  const int k0 = cb * kBlock;
  if (h < 0 || h >= s.ih || k0 >= s.ic) return l;
  if (k0 < x.a_c) {
    const int a_cb = (x.a_c + kBlock - 1) / kBlock;
    l.a = x.a + ((std::ptrdiff_t(n) * a_cb + cb) * s.ih + h) * s.iw * kBlock;
    l.from = k0 + kBlock <= x.a_c || !x.b ? From::a : From::a_b_halves;
    if (l.from == From::a) return l;
  } else {
    l.from = (k0 - x.a_c) % kBlock ? From::b_halves : From::b;
  }
  const std::ptrdiff_t hb = h - x.top;
  if (hb < 0 || hb >= x.b_h) return l;
  const int b_cb = (x.b_c + kBlock - 1) / kBlock, j = k0 < x.a_c ? 0 : (k0 - x.a_c) / kBlock;
  const auto row = [&](int blk) {
    return blk < b_cb ? x.b + ((std::ptrdiff_t(n) * b_cb + blk) * x.b_h + hb) * x.b_w * kBlock : nullptr;
  };
  l.b0 = row(j);
  if (l.from == From::b_halves) l.b1 = row(j + 1);
  return l;
}

// The block's 16 channels at input column w (inside the input).
inline __m512 block_at(const BlockLine& l, const Source& x, std::ptrdiff_t w) {
  const __m512 z = _mm512_setzero_ps();
  if (l.from == From::zeros) return z;
  if (l.from == From::a) return _mm512_loadu_ps(l.a + w * kBlock);
  const std::ptrdiff_t bw = w - x.left;
  const bool in_b = bw >= 0 && bw < x.b_w;
  const __m512 b0 = in_b && l.b0 ? _mm512_loadu_ps(l.b0 + bw * kBlock) : z;
  if (l.from == From::b) return b0;
  if (l.from == From::a_b_halves) return _mm512_shuffle_f32x4(_mm512_loadu_ps(l.a + w * kBlock), b0, 0x44);
  const __m512 b1 = in_b && l.b1 ? _mm512_loadu_ps(l.b1 + bw * kBlock) : z;
  return _mm512_shuffle_f32x4(b0, b1, 0x4E);
}

// One row of the padded plane's line: bf16 of blocks 2 ip and 2 ip + 1 (if any), or zeros.
void fill_line(const ConvShape& s, const Source& x, int n, int ip, std::ptrdiff_t line, std::ptrdiff_t wp,
               std::ptrdiff_t from, std::ptrdiff_t to, std::uint16_t* out) {
  const std::ptrdiff_t h = line - s.pad_h;
  const BlockLine lo = block_line(s, x, n, 2 * ip, h), hi = block_line(s, x, n, 2 * ip + 1, h);
  for (std::ptrdiff_t r = from; r < to; ++r) {
    const std::ptrdiff_t w = r - line * wp - s.pad_w;
    __m512i v = _mm512_setzero_si512();
    if (lo.from != From::zeros && w >= 0 && w < s.iw) v = (__m512i)_mm512_cvtne2ps_pbh(block_at(hi, x, w), block_at(lo, x, w));
    _mm512_storeu_si512(out + r * 32, v);
  }
}

// A convolution's padded bf16 input plane, per image and input pair: pitch wp, and rows for
// tasks_m tasks of 32 output rows plus the last task's reach past them ((kh-1) lines and kw-1 rows).
struct Geometry {
  int icp;
  std::ptrdiff_t wp, tasks_m, rows, lines;
  explicit Geometry(const ConvShape& s)
      : icp(bf16_pairs(s.icb())),
        wp(s.iw + 2 * s.pad_w),
        tasks_m((std::ptrdiff_t(s.oh()) * wp + 31) / 32),
        rows((tasks_m * 32 + (s.kh - 1) * wp + s.kw - 1 + 15) / 16 * 16),
        lines((rows + wp - 1) / wp) {}
  std::ptrdiff_t image_halves() const { return std::ptrdiff_t(icp) * rows * 32; }
};

void fill_plane(const ConvShape& s, const Geometry& g, const Source& x, std::uint16_t* xb) {
#pragma omp for collapse(3) schedule(static)
  for (int n = 0; n < s.n; ++n)
    for (int ip = 0; ip < g.icp; ++ip)
      for (std::ptrdiff_t line = 0; line < g.lines; ++line)
        fill_line(s, x, n, ip, line, g.wp, line * g.wp, line * g.wp + g.wp < g.rows ? line * g.wp + g.wp : g.rows,
                  xb + (std::ptrdiff_t(n) * g.icp + ip) * g.rows * 32);
}

// The rows of the plane of s's input that hold no input pixel (its padding, the tail), zeroed:
// what fill_plane writes there, for a plane whose pixels another convolution stores.
void zero_plane_borders(const ConvShape& s, const Geometry& g, std::uint16_t* xb) {
#pragma omp for collapse(3) schedule(static)
  for (int n = 0; n < s.n; ++n)
    for (int ip = 0; ip < g.icp; ++ip)
      for (std::ptrdiff_t line = 0; line < g.lines; ++line) {
        std::uint16_t* plane = xb + (std::ptrdiff_t(n) * g.icp + ip) * g.rows * 32;
        const std::ptrdiff_t from = line * g.wp, to = from + g.wp < g.rows ? from + g.wp : g.rows;
        const bool inside = line >= s.pad_h && line < s.pad_h + s.ih;
        for (std::ptrdiff_t r = from; r < to; ++r)
          if (!inside || r - from < s.pad_w || r - from >= s.pad_w + s.iw) _mm512_storeu_si512(plane + r * 32, _mm512_setzero_si512());
      }
}

// Where a task's rows go when the next convolution reads them (conv_pair_tiles): output pixel
// (h, w) is that convolution's input pixel, row (h + pad_h) * wp + w + pad_w of its plane.
struct PlaneOut {
  std::uint16_t* x;  // the next convolution's planes, all images
  const Geometry* g;
  int pad_h, pad_w;
};

// 16 rows from r0 of blocks nb (c0) and nb + 1 (c1; null: none), plus bias, ReLU if asked, as
// the bf16 pair nb / 2 of the next convolution's plane: what fill_line would make of the fp32
// store_rows gives.
void store_plane_rows(const Out& o, const PlaneOut& p, std::uint16_t* plane, const float* c0, const float* c1,
                      std::ptrdiff_t r0, int nb) {
  const __m512 z = _mm512_setzero_ps();
  const __m512 b0 = o.bias ? _mm512_loadu_ps(o.bias + nb * kBlock) : z;
  const __m512 b1 = o.bias && c1 ? _mm512_loadu_ps(o.bias + (nb + 1) * kBlock) : z;
  std::uint16_t* dst = plane + std::ptrdiff_t(nb / 2) * p.g->rows * 32;
  std::ptrdiff_t h = r0 / o.wp, w = r0 % o.wp;
  for (int r = 0; r < 16 && h < o.OH; ++r) {
    if (w < o.OW) {
      __m512 v0 = _mm512_add_ps(_mm512_load_ps(c0 + r * 16), b0);
      __m512 v1 = c1 ? _mm512_add_ps(_mm512_load_ps(c1 + r * 16), b1) : z;
      if (o.relu) v0 = _mm512_max_ps(v0, z), v1 = _mm512_max_ps(v1, z);
      _mm512_storeu_si512(dst + ((h + p.pad_h) * p.g->wp + w + p.pad_w) * 32, (__m512i)_mm512_cvtne2ps_pbh(v1, v0));
    }
    if (++w == o.wp) w = 0, ++h;
  }
}

// The tile loop over a convolution's geometry s (stride 1; for the transposed convolution its
// 1x1 per phase, s.oc = 4 x its output channels in nb blocks), from its plane xb, into o (each
// image y_image floats on) or, where next is given, into the next convolution's plane.
void tile_loop(const ConvShape& s, const Geometry& g, int nblocks, const std::uint16_t* xb, const std::uint16_t* w,
               Out o, std::ptrdiff_t y_image, const PlaneOut* next) {
  const int tasks_o = (nblocks + 1) / 2;
  o.wp = g.wp;
  float* y0 = o.y;
  alignas(64) float c[2][16 * 16];
#pragma omp for collapse(3) schedule(static)
  for (int n = 0; n < s.n; ++n)
    for (int to = 0; to < tasks_o; ++to)
      for (std::ptrdiff_t tm = 0; tm < g.tasks_m; ++tm) {
        const int nb = 2 * to;
        const Plane p{xb + n * g.image_halves(), g.rows, g.wp};
        const std::uint16_t* wo = w + std::ptrdiff_t(nb) * g.icp * s.kh * s.kw * 512;
        const std::ptrdiff_t r0 = tm * 32;
        const bool two = nb + 1 < nblocks;
        if (two)
          accumulate<2>(p, wo, g.icp, s.kh, s.kw, r0);
        else
          accumulate<1>(p, wo, g.icp, s.kh, s.kw, r0);
        if (next) {
          std::uint16_t* plane = next->x + n * next->g->image_halves();
          _tile_stored(0, c[0], 64);
          if (two) _tile_stored(1, c[1], 64);
          store_plane_rows(o, *next, plane, c[0], two ? c[1] : nullptr, r0, nb);
          _tile_stored(2, c[0], 64);
          if (two) _tile_stored(3, c[1], 64);
          store_plane_rows(o, *next, plane, c[0], two ? c[1] : nullptr, r0 + 16, nb);
          continue;
        }
        Out on = o;
        on.y = y0 + n * y_image;
        _tile_stored(0, c[0], 64);
        store_rows(on, c[0], r0, nb);
        _tile_stored(2, c[0], 64);
        store_rows(on, c[0], r0 + 16, nb);
        if (two) {
          _tile_stored(1, c[0], 64);
          store_rows(on, c[0], r0, nb + 1);
          _tile_stored(3, c[0], 64);
          store_rows(on, c[0], r0 + 16, nb + 1);
        }
      }
}

// One convolution (or the transposed one's 1x1 per phase) from x into o.
void run_tiles(const ConvShape& s, int nblocks, const Source& x, const std::uint16_t* w, const Out& o,
               std::ptrdiff_t y_image) {
  const Geometry g(s);
  auto* xb = reinterpret_cast<std::uint16_t*>(thread_scratch(std::size_t(s.n * g.image_halves() + 1) / 2));
  on_team([&] {
    fill_plane(s, g, x, xb);
    configure_tiles();
    tile_loop(s, g, nblocks, xb, w, o, y_image, nullptr);
    _tile_release();
  });
}

Source source_of(const ConvShape& s, const ConcatInput& in) {
  return in.b ? Source{in.a, in.a_c, in.b, in.b_c, in.b_h, in.b_w, in.top, in.left} : Source{in.a, s.ic};
}

void conv_tiles(const ConvShape& s, const float* x, const std::uint16_t* w, const float* bias, float* y) {
  const Out o{y, bias, s.oh(), s.ow(), s.ocb(), 0, 1, s.relu};
  run_tiles(s, s.ocb(), Source{x, s.ic}, w, o, std::ptrdiff_t(s.ocb()) * s.oh() * s.ow() * kBlock);
}

void conv_cat_tiles(const ConvShape& s, const ConcatInput& in, const std::uint16_t* w, const float* bias, float* y) {
  const Out o{y, bias, s.oh(), s.ow(), s.ocb(), 0, 1, s.relu};
  run_tiles(s, s.ocb(), source_of(s, in), w, o, std::ptrdiff_t(s.ocb()) * s.oh() * s.ow() * kBlock);
}

// s1 then s2, the first's output stored straight into the second's plane (conv_bf16.h).
void conv_pair_tiles(const ConvShape& s1, const ConcatInput& in, const std::uint16_t* w1, const float* bias1,
                     const ConvShape& s2, const std::uint16_t* w2, const float* bias2, float* y) {
  const Geometry g1(s1), g2(s2);
  const std::ptrdiff_t h1 = s1.n * g1.image_halves(), h2 = s2.n * g2.image_halves();
  auto* x1 = reinterpret_cast<std::uint16_t*>(thread_scratch(std::size_t(h1 + h2 + 1) / 2));
  std::uint16_t* x2 = x1 + h1;  // h1 is a multiple of 32 halves: x2 stays 64-byte aligned
  const Out o1{nullptr, bias1, s1.oh(), s1.ow(), s1.ocb(), 0, 1, s1.relu};
  const Out o2{y, bias2, s2.oh(), s2.ow(), s2.ocb(), 0, 1, s2.relu};
  const PlaneOut next{x2, &g2, s2.pad_h, s2.pad_w};
  const Source x = source_of(s1, in);
  on_team([&] {
    fill_plane(s1, g1, x, x1);
    zero_plane_borders(s2, g2, x2);
    configure_tiles();
    tile_loop(s1, g1, s1.ocb(), x1, w1, o1, 0, &next);
    tile_loop(s2, g2, s2.ocb(), x2, w2, o2, std::ptrdiff_t(s2.ocb()) * s2.oh() * s2.ow() * kBlock, nullptr);
    _tile_release();
  });
}

void deconv2x2_tiles(const DeconvShape& d, const float* x, const std::uint16_t* w, const float* bias, float* y) {
  ConvShape s;  // the transposed convolution's 1x1 over its input, four phases of outputs
  s.n = d.n; s.ic = d.ic; s.ih = d.ih; s.iw = d.iw; s.kh = s.kw = 1;
  const int OCB = d.ocb();
  s.oc = 4 * OCB * kBlock;
  const Out o{y, bias, d.oh(), d.ow(), OCB, 0, 2, false};
  run_tiles(s, 4 * OCB, Source{x, s.ic}, w, o, std::ptrdiff_t(OCB) * d.oh() * d.ow() * kBlock);
}

}  // namespace

// Only this table leaves the file (scripts/check-isa-leaks: no exported function may touch
// ymm/zmm registers, since baseline code could call it on any CPU).
extern const AmxBf16Kernels amx_bf16_kernels{conv_tiles, conv_cat_tiles, conv_pair_tiles, deconv2x2_tiles};

}  // namespace yelan::kernels
