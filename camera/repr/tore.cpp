#include "camera/repr/tore.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "camera/repr/tore_kernels.h"

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
// Rows are independent, so `threads` > 1 splits them with OpenMP.
template <class Kernel>
void readout_planes(const std::vector<std::int64_t>& fifo, int width, int height, int k,
                    const ToreReadoutParams& params, Kernel kernel, float* out, int threads) {
  constexpr int kBuffer = 1536;
  const int channels = 2 * k;
  const int chunk = std::max(1, kBuffer / channels);
  const std::size_t plane = std::size_t(width) * height;
#pragma omp parallel for num_threads(threads) schedule(static) if (threads > 1)
  for (int y = 0; y < height; ++y) {
    float buf[kBuffer];
    for (int x0 = 0; x0 < width; x0 += chunk) {
      const int n = std::min(chunk, width - x0);
      kernel(fifo.data() + (std::size_t(y) * width + x0) * channels, std::size_t(n) * channels,
             params, buf);
      scatter_planes(buf, n, channels, plane, out + std::size_t(y) * width + x0);
    }
  }
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

void ToreVolume::readout(std::int64_t t_us, float* out, int threads) const {
  const float ln_tau = static_cast<float>(std::log(static_cast<double>(tau_)));
  // clamp(1 - ln(1 + a) / ln(tau), 0, 0.7) / 0.7 == clamp(1/0.7 - ln(1 + a) / (0.7 ln(tau)), 0, 1)
  const ToreReadoutParams p{t_us, static_cast<std::uint64_t>(tau_), 1.f / 0.7f, 1.f / (0.7f * ln_tau)};
  readout_planes(fifo_, width_, height_, k_, p, tore_kernels(kernels::active_isa()).yelan, out,
                 std::max(threads, 1));
}

void ToreVolume::readout_baldwin(std::int64_t t_us, float* out, BaldwinScale scale, int threads) const {
  if (scale.min_t_us < 0 || scale.max_t_us <= scale.min_t_us || scale.max_t_us > kMaxHorizon)
    throw std::invalid_argument("TORE (Baldwin): need 0 <= min_t < max_t <= 2^31-1 us, got " +
                                std::to_string(scale.min_t_us) + ", " + std::to_string(scale.max_t_us));
  const ToreReadoutParams p{t_us, static_cast<std::uint64_t>(scale.max_t_us),
                            static_cast<float>(std::log1p(static_cast<double>(scale.min_t_us))), 1.f};
  readout_planes(fifo_, width_, height_, k_, p, tore_kernels(kernels::active_isa()).baldwin, out,
                 std::max(threads, 1));
}

}  // namespace yelan::camera
