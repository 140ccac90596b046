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

// One row of the padded plane's line: bf16 of blocks cb and cb+1 (if any), or zeros.
void fill_line(const ConvShape& s, const float* x, int n, int ip, std::ptrdiff_t line, std::ptrdiff_t wp,
               std::ptrdiff_t from, std::ptrdiff_t to, std::uint16_t* out) {
  const int ICB = s.icb(), cb = 2 * ip;
  const std::ptrdiff_t h = line - s.pad_h;
  const std::ptrdiff_t plane = std::ptrdiff_t(s.ih) * s.iw * kBlock;
  const float* x0 = h >= 0 && h < s.ih ? x + (std::ptrdiff_t(n) * ICB + cb) * plane + h * s.iw * kBlock : nullptr;
  const float* x1 = x0 && cb + 1 < ICB ? x0 + plane : nullptr;
  for (std::ptrdiff_t r = from; r < to; ++r) {
    const std::ptrdiff_t w = r - line * wp - s.pad_w;
    __m512i v = _mm512_setzero_si512();
    if (x0 && w >= 0 && w < s.iw) {
      const __m512 lo = _mm512_loadu_ps(x0 + w * kBlock);
      const __m512 hi = x1 ? _mm512_loadu_ps(x1 + w * kBlock) : _mm512_setzero_ps();
      v = (__m512i)_mm512_cvtne2ps_pbh(hi, lo);
    }
    _mm512_storeu_si512(out + r * 32, v);
  }
}

// The tile loop over a convolution's geometry s (stride 1; for the transposed convolution
// its 1x1 per phase, s.oc = 4 x its output channels in nb blocks), into o.
void run_tiles(const ConvShape& s, int nblocks, const float* x, const std::uint16_t* w, Out o, std::ptrdiff_t y_image) {
  const int ICP = bf16_pairs(s.icb());
  const std::ptrdiff_t wp = s.iw + 2 * s.pad_w;
  const std::ptrdiff_t tasks_m = (std::ptrdiff_t(s.oh()) * wp + 31) / 32;  // 32 task rows each
  // The last task's rows read up to (kh-1) lines and kw-1 rows past its own.
  const std::ptrdiff_t rows = (tasks_m * 32 + (s.kh - 1) * wp + s.kw - 1 + 15) / 16 * 16;
  const std::ptrdiff_t lines = (rows + wp - 1) / wp;
  const std::ptrdiff_t x_halves = std::ptrdiff_t(s.n) * ICP * rows * 32;
  auto* xb = reinterpret_cast<std::uint16_t*>(thread_scratch(std::size_t(x_halves + 1) / 2));
  const int tasks_o = (nblocks + 1) / 2;
  o.wp = wp;
  float* y0 = o.y;
  on_team([&] {
#pragma omp for collapse(3) schedule(static)
    for (int n = 0; n < s.n; ++n)
      for (int ip = 0; ip < ICP; ++ip)
        for (std::ptrdiff_t line = 0; line < lines; ++line)
          fill_line(s, x, n, ip, line, wp, line * wp, line * wp + wp < rows ? line * wp + wp : rows,
                    xb + (std::ptrdiff_t(n) * ICP + ip) * rows * 32);
    configure_tiles();
    alignas(64) float c[16 * 16];
#pragma omp for collapse(3) schedule(static)
    for (int n = 0; n < s.n; ++n)
      for (int to = 0; to < tasks_o; ++to)
        for (std::ptrdiff_t tm = 0; tm < tasks_m; ++tm) {
          const int nb = 2 * to;
          const Plane p{xb + std::ptrdiff_t(n) * ICP * rows * 32, rows, wp};
          const std::uint16_t* wo = w + std::ptrdiff_t(nb) * ICP * s.kh * s.kw * 512;
          const std::ptrdiff_t r0 = tm * 32;
          const bool two = nb + 1 < nblocks;
          if (two)
            accumulate<2>(p, wo, ICP, s.kh, s.kw, r0);
          else
            accumulate<1>(p, wo, ICP, s.kh, s.kw, r0);
          Out on = o;
          on.y = y0 + n * y_image;
          _tile_stored(0, c, 64);
          store_rows(on, c, r0, nb);
          _tile_stored(2, c, 64);
          store_rows(on, c, r0 + 16, nb);
          if (two) {
            _tile_stored(1, c, 64);
            store_rows(on, c, r0, nb + 1);
            _tile_stored(3, c, 64);
            store_rows(on, c, r0 + 16, nb + 1);
          }
        }
    _tile_release();
  });
}

void conv_tiles(const ConvShape& s, const float* x, const std::uint16_t* w, const float* bias, float* y) {
  const Out o{y, bias, s.oh(), s.ow(), s.ocb(), 0, 1, s.relu};
  run_tiles(s, s.ocb(), x, w, o, std::ptrdiff_t(s.ocb()) * s.oh() * s.ow() * kBlock);
}

void deconv2x2_tiles(const DeconvShape& d, const float* x, const std::uint16_t* w, const float* bias, float* y) {
  ConvShape s;  // the transposed convolution's 1x1 over its input, four phases of outputs
  s.n = d.n; s.ic = d.ic; s.ih = d.ih; s.iw = d.iw; s.kh = s.kw = 1;
  const int OCB = d.ocb();
  s.oc = 4 * OCB * kBlock;
  const Out o{y, bias, d.oh(), d.ow(), OCB, 0, 2, false};
  run_tiles(s, 4 * OCB, x, w, o, std::ptrdiff_t(OCB) * d.oh() * d.ow() * kBlock);
}

}  // namespace

// Only this table leaves the file (scripts/check-isa-leaks: no exported function may touch
// ymm/zmm registers, since baseline code could call it on any CPU).
extern const AmxBf16Kernels amx_bf16_kernels{conv_tiles, deconv2x2_tiles};

}  // namespace yelan::kernels
