#include "engine/input.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

namespace yelan::input {

namespace {

// A TORE of `channels` planes at sensor_w x sensor_h fills input `a` at downscale d, or throws.
void require_fills(int channels, int sensor_w, int sensor_h, const layers::Act& a, int d) {
  if (channels != a.c || std::size_t(a.h) * d > std::size_t(sensor_h) || std::size_t(a.w) * d > std::size_t(sensor_w))
    throw std::invalid_argument("TORE of " + std::to_string(channels) + " channels at " + std::to_string(sensor_w) + "x" +
                                std::to_string(sensor_h) + " does not fill an input of " + std::to_string(a.c) + "x" +
                                std::to_string(a.w) + "x" + std::to_string(a.h) + " at downscale " + std::to_string(d));
}

// The logit a sigmoid cut in (0, 1) corresponds to: comparing logits spares a sigmoid a pixel.
float logit_of_cut(float cut, const char* who) {
  if (!(cut > 0 && cut < 1)) throw std::invalid_argument(std::string(who) + ": the cut must lie in (0, 1)");
  return std::log(cut / (1 - cut));
}

}  // namespace

void downscale_tore(const std::vector<float>& vol, int sensor_h, int sensor_w, int d, const layers::Act& a, int n) {
  downscale_tore(vol, sensor_h, sensor_w, d, a, n, camera::PixelRect{0, 0, a.w, a.h});
}

void downscale_tore(const std::vector<float>& vol, int sensor_h, int sensor_w, int d, const layers::Act& a, int n,
                    camera::PixelRect r) {
  const int C = a.c, H = a.h, W = a.w;
  if (vol.size() != std::size_t(C) * sensor_h * sensor_w)
    throw std::invalid_argument("TORE volume of " + std::to_string(vol.size()) + " values is not " + std::to_string(C) +
                                " channels of " + std::to_string(sensor_w) + "x" + std::to_string(sensor_h));
  require_fills(C, sensor_w, sensor_h, a, d);
  r = r.clipped(W, H);
  if (r.empty()) return;
  const float inv = 1.f / float(d * d);
  // Row sums first (contiguous, vectorised), then one strided store per output value into
  // the 16-lane layout; the additions run in the plain (dy, dx) order, so the result is
  // bit-identical to summing each cell on its own.
  const int rw = r.width();
  std::vector<float> row(static_cast<std::size_t>(rw));
  for (int c = 0; c < C; ++c) {
    float* out = a.data + (std::size_t(n) * a.cb() + c / 16) * a.pixels() * 16 + c % 16;
    const float* in = vol.data() + std::size_t(c) * sensor_h * sensor_w + std::size_t(r.x0) * d;
    for (int y = r.y0; y < r.y1; ++y) {
      const float* r0 = in + std::size_t(y) * d * sensor_w;
      if (d == 2) {
        const float* r1 = r0 + sensor_w;
        for (int x = 0; x < rw; ++x) row[std::size_t(x)] = r0[2 * x] + r0[2 * x + 1] + r1[2 * x] + r1[2 * x + 1];
      } else {
        std::fill(row.begin(), row.end(), 0.f);
        for (int dy = 0; dy < d; ++dy)
          for (int x = 0; x < rw; ++x)
            for (int dx = 0; dx < d; ++dx) row[std::size_t(x)] += r0[std::size_t(dy) * sensor_w + x * d + dx];
      }
      float* o = out + (std::size_t(y) * W + r.x0) * 16;
      for (int x = 0; x < rw; ++x) o[std::size_t(x) * 16] = row[std::size_t(x)] * inv;
    }
  }
}

void tore_input(const camera::ToreVolume& tore, std::int64_t t, int d, const layers::Act& a, int n,
                camera::PixelRect r) {
  require_fills(tore.channels(), tore.width(), tore.height(), a, d);
  r = {std::max(r.x0, 0), std::max(r.y0, 0), std::min(r.x1, a.w), std::min(r.y1, a.h)};
  if (a.c > 16) {  // more than one channel block: not pixel-interleaved, go through the volume
    std::vector<float> vol(tore.volume_size());
    tore.readout(t, vol.data(), camera::PixelRect{r.x0 * d, r.y0 * d, r.x1 * d, r.y1 * d});
    downscale_tore(vol, tore.height(), tore.width(), d, a, n, r);
    return;
  }
  tore.readout_mean(t, d, a.data + std::size_t(n) * a.cb() * a.pixels() * 16, a.w, 16, r);
}

void mask_cut(const layers::Act& logits, int n, int channel, std::vector<float>& keep, float cut) {
  if (channel < 0 || channel >= logits.c || n < 0 || n >= logits.n) throw std::invalid_argument("mask_cut: no such frame or channel");
  const float logit_cut = logit_of_cut(cut, "mask_cut");
  keep.resize(logits.pixels());
  const float* p = logits.data + (std::size_t(n) * logits.cb() + channel / 16) * logits.pixels() * 16 + channel % 16;
  for (std::size_t i = 0; i < keep.size(); ++i) keep[i] = p[i * 16] > logit_cut ? 1.f : 0.f;
}

void mask_cut_all(const layers::Act& logits, int n, float cut, std::vector<std::vector<float>>& keep,
                  std::vector<MaskExtent>& extent, int first, int end) {
  if (end < 0) end = logits.c;
  if (n < 0 || n >= logits.n || first < 0 || end > logits.c || first > end)
    throw std::invalid_argument("mask_cut_all: no such frame or channel");
  const float logit_cut = logit_of_cut(cut, "mask_cut_all");
  const std::size_t P = logits.pixels();
  keep.resize(std::size_t(logits.c));
  extent.assign(std::size_t(logits.c), MaskExtent{0, logits.w, logits.h, 0, 0});
  for (int c = 0; c < logits.c; ++c)
    if (c < first || c >= end) keep[std::size_t(c)].clear();
    else keep[std::size_t(c)].assign(P, 0.f);
  for (int cb = first / 16; cb < (end + 15) / 16; ++cb) {
    const float* p = logits.data + (std::size_t(n) * logits.cb() + cb) * P * 16;
    const int lo = std::max(first - cb * 16, 0), hi = std::min(16, end - cb * 16);
    // Only the block's channels to cut are compared: under an age cap that is 2-4 of 16.
    for (int y = 0; y < logits.h; ++y)
      for (int x = 0; x < logits.w; ++x) {
        const std::size_t i = std::size_t(y) * logits.w + x;
        for (int l = lo; l < hi; ++l) {
          if (!(p[i * 16 + l] > logit_cut)) continue;
          const int c = cb * 16 + l;
          keep[std::size_t(c)][i] = 1.f;
          MaskExtent& e = extent[std::size_t(c)];
          ++e.kept;
          e.x0 = std::min(e.x0, x), e.y0 = std::min(e.y0, y);
          e.x1 = std::max(e.x1, x + 1), e.y1 = std::max(e.y1, y + 1);
        }
      }
  }
  for (MaskExtent& e : extent)
    if (e.kept == 0) e = MaskExtent{};
}

void grow_mask(std::vector<float>& keep, int h, int w, int r) {
  if (r < 0 || h < 0 || w < 0 || keep.size() != std::size_t(h) * std::size_t(w))
    throw std::invalid_argument("grow_mask: need r >= 0 and an h x w mask");
  if (r == 0) return;
  // Along one line of n values `stride` apart: each becomes 1 when a 1 lies within r of it.
  const auto line = [r](float* p, int n, std::size_t stride, std::vector<float>& tmp) {
    tmp.assign(std::size_t(n), 0.f);
    int last = -(1 << 30);  // the latest 1 at or before i, then the next at or after it
    for (int i = 0; i < n; ++i) {
      if (p[std::size_t(i) * stride] != 0) last = i;
      if (i - last <= r) tmp[std::size_t(i)] = 1.f;
    }
    int next = 1 << 30;
    for (int i = n - 1; i >= 0; --i) {
      if (p[std::size_t(i) * stride] != 0) next = i;
      if (next - i <= r) tmp[std::size_t(i)] = 1.f;
    }
    for (int i = 0; i < n; ++i) p[std::size_t(i) * stride] = tmp[std::size_t(i)];
  };
  std::vector<float> tmp;
  for (int y = 0; y < h; ++y) line(keep.data() + std::size_t(y) * w, w, 1, tmp);
  for (int x = 0; x < w; ++x) line(keep.data() + x, h, std::size_t(w), tmp);
}

void apply_mask(const layers::Act& a, int n, const std::vector<float>& keep) {
  apply_mask(a, n, keep, camera::PixelRect{0, 0, a.w, a.h});
}

void apply_mask(const layers::Act& a, int n, const std::vector<float>& keep, camera::PixelRect r) {
  for (int cb = 0; cb < a.cb(); ++cb) {
    float* p = a.data + (std::size_t(n) * a.cb() + cb) * a.pixels() * 16;
    for (int y = r.y0; y < r.y1; ++y)
      for (std::size_t i = std::size_t(y) * a.w + r.x0; i < std::size_t(y) * a.w + r.x1; ++i)
        for (int l = 0; l < 16; ++l) p[i * 16 + l] *= keep[i];
  }
}

void mask_stage2_input(const layers::Act& a, int n, const std::vector<float>& keep, bool outside, int margin) {
  if (!outside) return apply_mask(a, n, keep);
  const int c = a.c / 2, H = a.h, W = a.w;
  if (a.c % 2 || a.cb() != 1 || keep.size() != a.pixels())
    throw std::invalid_argument("outside input: " + std::to_string(a.c) + " channels of " + std::to_string(W) + "x" +
                                std::to_string(H) + " behind a mask of " + std::to_string(keep.size()) +
                                " pixels (needs an even count of at most 16, and one mask value a pixel)");
  int x0 = 0, y0 = 0, x1 = W, y1 = H;  // the region whose outside events stage 2 reads
  if (margin > 0) {
    x0 = W, y0 = H, x1 = 0, y1 = 0;
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x)
        if (keep[std::size_t(y) * W + x] != 0.f)
          x0 = std::min(x0, x), x1 = std::max(x1, x + 1), y0 = std::min(y0, y), y1 = std::max(y1, y + 1);
    if (x1 == 0) x0 = y0 = 0;  // nobody: no region (as an empty crop)
    else x0 = std::max(x0 - margin, 0), y0 = std::max(y0 - margin, 0), x1 = std::min(x1 + margin, W), y1 = std::min(y1 + margin, H);
  }
  float* p = a.data + std::size_t(n) * a.pixels() * 16;
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      float* v = p + (std::size_t(y) * W + x) * 16;
      const float k = keep[std::size_t(y) * W + x];
      const bool in_region = x >= x0 && x < x1 && y >= y0 && y < y1;
      for (int l = 0; l < c; ++l) {
        v[c + l] = in_region ? v[l] * (1.f - k) : 0.f;
        v[l] *= k;
      }
    }
}

}  // namespace yelan::input
