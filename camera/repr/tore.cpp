#include "camera/repr/tore.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "camera/repr/tore_kernels.h"
#include "kernels/parallel.h"

namespace yelan::camera {
namespace {

constexpr std::int64_t kMaxHorizon = (std::int64_t{1} << 31) - 1;  // ages are cast via int32

template <int K>
void update_fixed(std::int64_t* fifo, int width, int height, std::span<const Event> events,
                  std::uint64_t& out_of_range) {
  for (const Event& e : events) {
    if (e.x >= width || e.y >= height) {
      ++out_of_range;
      continue;
    }
    std::int64_t* s = fifo + ((std::size_t(e.y) * width + e.x) * 2 + (e.p ? 0 : 1)) * K;
    for (int i = K - 1; i > 0; --i) s[i] = s[i - 1];
    s[0] = e.t;
  }
}

// De-interleaves n pixels of `channels` values each ([x][channel]) into channel planes.
// The channel count is a template parameter for the common depths so the loops unroll.
template <int C>
void scatter_fixed(const float* buf, int n, std::size_t plane, float* dst) {
  for (int i = 0; i < n; ++i)
    for (int c = 0; c < C; ++c) dst[c * plane + i] = buf[i * C + c];
}
void scatter_planes(const float* buf, int n, int channels, std::size_t plane, float* dst) {
  switch (channels) {
    case 2: return scatter_fixed<2>(buf, n, plane, dst);
    case 4: return scatter_fixed<4>(buf, n, plane, dst);
    case 6: return scatter_fixed<6>(buf, n, plane, dst);
    case 8: return scatter_fixed<8>(buf, n, plane, dst);
    default:
      for (int c = 0; c < channels; ++c)
        for (int i = 0; i < n; ++i) dst[c * plane + i] = buf[i * channels + c];
  }
}

// Runs `kernel` over the FIFO in row chunks that fit a stack buffer and scatters each
// chunk from the FIFO's pixel-major order to the output's channel-major planes.
// Rows are independent, so `threads` > 1 splits them with OpenMP (kernels/parallel.h).
// Only the pixels of `rect` (already clipped to the sensor) are read and written.
template <class Kernel>
void readout_planes(const std::vector<std::int64_t>& fifo, int width, int height, int k,
                    const ToreReadoutParams& params, Kernel kernel, float* out, int threads, PixelRect rect) {
  constexpr int kBuffer = 1536;
  const int channels = 2 * k;
  const int chunk = std::max(1, kBuffer / channels);
  const std::size_t plane = std::size_t(width) * height;
  kernels::on_threads(threads, [&] {
#pragma omp for schedule(static)
    for (int y = rect.y0; y < rect.y1; ++y) {
      float buf[kBuffer];
      for (int x0 = rect.x0; x0 < rect.x1; x0 += chunk) {
        const int n = std::min(chunk, rect.x1 - x0);
        kernel(fifo.data() + (std::size_t(y) * width + x0) * channels, std::size_t(n) * channels,
               params, buf);
        scatter_planes(buf, n, channels, plane, out + std::size_t(y) * width + x0);
      }
    }
  });
}

}  // namespace

ToreVolume::ToreVolume(int width, int height, ToreOptions options)
    : width_(width), height_(height), k_(options.k), tau_(options.tau_us) {
  if (width <= 0 || height <= 0 || width > 65536 || height > 65536)
    throw std::invalid_argument("TORE: sensor size " + std::to_string(width) + "x" +
                                std::to_string(height) + " is outside 1..65536");
  if (k_ < 1 || k_ > 64)
    throw std::invalid_argument("TORE: k = " + std::to_string(k_) + " is outside 1..64");
  if (tau_ < 2 || tau_ > kMaxHorizon)
    throw std::invalid_argument("TORE: tau = " + std::to_string(tau_) +
                                " us is outside 2..2147483647");
  fifo_.assign(std::size_t(width) * height * 2 * k_, kEmpty);
}

void ToreVolume::reset() {
  std::fill(fifo_.begin(), fifo_.end(), kEmpty);
  out_of_range_ = 0;
}

void ToreVolume::update(std::span<const Event> events) {
  switch (k_) {
    case 1: return update_fixed<1>(fifo_.data(), width_, height_, events, out_of_range_);
    case 2: return update_fixed<2>(fifo_.data(), width_, height_, events, out_of_range_);
    case 3: return update_fixed<3>(fifo_.data(), width_, height_, events, out_of_range_);
    case 4: return update_fixed<4>(fifo_.data(), width_, height_, events, out_of_range_);
    default:
      for (const Event& e : events) update(e);
  }
}

namespace {
// The common case of readout_mean (K = 3, d = 2) with the channel count known, so the loops
// unroll; the sum runs in the general loop's order ((r0 x0 + r0 x1) + r1 x0) + r1 x1 (no read-out
// value is -0, so starting from r0 x0 instead of 0 changes no bit).
template <int C>
void cell_means_2x2(const float* r0, const float* r1, int n, float inv, float* o, int pixel_stride) {
  for (int x = 0; x < n; ++x, r0 += 2 * C, r1 += 2 * C, o += pixel_stride)
    for (int c = 0; c < C; ++c) o[c] = (((r0[c] + r0[C + c]) + r1[c]) + r1[C + c]) * inv;
}

// clamp(1 - ln(1 + a) / ln(tau), 0, 0.7) / 0.7 == clamp(1/0.7 - ln(1 + a) / (0.7 ln(tau)), 0, 1)
ToreReadoutParams yelan_params(std::int64_t t_us, std::int64_t tau) {
  const float ln_tau = static_cast<float>(std::log(static_cast<double>(tau)));
  return {t_us, static_cast<std::uint64_t>(tau), 1.f / 0.7f, 1.f / (0.7f * ln_tau)};
}
}  // namespace

void ToreVolume::readout(std::int64_t t_us, float* out, int threads) const {
  readout_planes(fifo_, width_, height_, k_, yelan_params(t_us, tau_), tore_kernels(kernels::active_isa()).yelan,
                 out, std::max(threads, 1), PixelRect{0, 0, width_, height_});
}

void ToreVolume::readout(std::int64_t t_us, float* out, PixelRect r) const {
  r = {std::max(r.x0, 0), std::max(r.y0, 0), std::min(r.x1, width_), std::min(r.y1, height_)};
  if (r.empty()) return;
  readout_planes(fifo_, width_, height_, k_, yelan_params(t_us, tau_), tore_kernels(kernels::active_isa()).yelan,
                 out, 1, r);
}

void ToreVolume::readout_mean(std::int64_t t_us, int d, float* out, int out_width, int pixel_stride,
                              PixelRect r) const {
  if (d < 1 || pixel_stride < channels() || out_width < 1)
    throw std::invalid_argument("TORE: readout_mean needs d >= 1 and pixel_stride >= " + std::to_string(channels()));
  r = {std::max(r.x0, 0), std::max(r.y0, 0), std::min({r.x1, width_ / d, out_width}), std::min(r.y1, height_ / d)};
  if (r.empty()) return;
  const int C = channels(), n = r.x1 - r.x0;
  const std::size_t row_values = std::size_t(n) * d * C;  // one sensor row of the cells, [x][channel]
  std::vector<float> rows(row_values * std::size_t(d));
  const ToreReadoutParams p = yelan_params(t_us, tau_);
  const auto kernel = tore_kernels(kernels::active_isa()).yelan;
  const float inv = 1.f / float(d * d);
  for (int y = r.y0; y < r.y1; ++y) {
    for (int dy = 0; dy < d; ++dy)
      kernel(fifo_.data() + (std::size_t(y * d + dy) * width_ + std::size_t(r.x0) * d) * C, row_values, p,
             rows.data() + std::size_t(dy) * row_values);
    float* o = out + (std::size_t(y) * out_width + r.x0) * pixel_stride;
    if (d == 2 && C == 6) {
      cell_means_2x2<6>(rows.data(), rows.data() + row_values, n, inv, o, pixel_stride);
      continue;
    }
    for (int x = 0; x < n; ++x)
      for (int c = 0; c < C; ++c) {
        float sum = 0;
        for (int dy = 0; dy < d; ++dy)
          for (int dx = 0; dx < d; ++dx) sum += rows[std::size_t(dy) * row_values + (std::size_t(x) * d + dx) * C + c];
        o[std::size_t(x) * pixel_stride + c] = sum * inv;
      }
  }
}

void ToreVolume::readout_baldwin(std::int64_t t_us, float* out, BaldwinScale scale, int threads) const {
  if (scale.min_t_us < 0 || scale.max_t_us <= scale.min_t_us || scale.max_t_us > kMaxHorizon)
    throw std::invalid_argument("TORE (Baldwin): need 0 <= min_t < max_t <= 2^31-1 us, got " +
                                std::to_string(scale.min_t_us) + ", " + std::to_string(scale.max_t_us));
  const ToreReadoutParams p{t_us, static_cast<std::uint64_t>(scale.max_t_us),
                            static_cast<float>(std::log1p(static_cast<double>(scale.min_t_us))), 1.f};
  readout_planes(fifo_, width_, height_, k_, p, tore_kernels(kernels::active_isa()).baldwin, out,
                 std::max(threads, 1), PixelRect{0, 0, width_, height_});
}

}  // namespace yelan::camera
