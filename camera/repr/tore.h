// TORE volume (Baldwin et al. 2021, "Time-Ordered Recent Event (TORE) Volumes for Event
// Cameras", with YeLan's read-out; SPEC section 3). Per pixel and polarity a FIFO of the K
// most recent event timestamps, updated per event in O(1) without allocation, and read
// out at any time T into a float volume of 2K channels x H x W (channel-major): channels
// pos0..pos{K-1} then neg0..neg{K-1}, slot 0 the newest.
//
// Read-outs (cost independent of how many events arrived since the last one):
//  - readout(T, out): YeLan. age = T - t_k (us); v = ln(1 + age) / ln(tau);
//    value = clamp(1 - v, 0, 0.7) / 0.7. An empty slot, age >= tau, or age < 0 (an event
//    newer than T: not yet arrived at T) reads 0. Such a future event is not skipped over:
//    its slot reads 0 and the older slots keep their positions, so reading at a T older
//    than the last update is approximate (events it pushed out are gone).
//  - readout_baldwin(T, out): the original TORE scaling, as in the authors' published
//    events2ToreFeature: age is clipped to max_t (5e6 us); an empty or future slot counts
//    as max_t; value = max(0, ln(age + 1) - ln(min_t + 1)), min_t = 150 us. So the newest
//    events read 0 and missing or old ones read ln(5e6 + 1) - ln(151) ~ 10.41 (no
//    rescaling to [0, 1], and the opposite direction to YeLan's). The original builds the
//    volume from events strictly before T; here an event at exactly T is included (age 0).
#pragma once
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "camera/event.h"
#include "camera/pixel_rect.h"

namespace yelan::camera {

struct ToreOptions {
  int k = 3;                          // FIFO depth per pixel and polarity, 1..64
  std::int64_t tau_us = 5'000'000;    // YeLan's horizon: ages >= tau read 0; 2..2^31-1
};

struct BaldwinScale {
  std::int64_t min_t_us = 150;        // ages up to this read 0
  std::int64_t max_t_us = 5'000'000;  // ages clip here; empty slots count as this
};

class ToreVolume {
 public:
  // Marks an empty slot. Timestamps are unsigned-wrapped differences at read-out, so any
  // read-out time T above INT64_MIN + 2^31 sees an empty slot as older than every horizon.
  static constexpr std::int64_t kEmpty = std::numeric_limits<std::int64_t>::min();

  // Throws std::invalid_argument on a non-positive size, k outside 1..64 or a bad tau.
  ToreVolume(int width, int height, ToreOptions options = {});

  int width() const { return width_; }
  int height() const { return height_; }
  int k() const { return k_; }
  int channels() const { return 2 * k_; }
  std::int64_t tau_us() const { return tau_; }
  std::size_t volume_size() const { return std::size_t(channels()) * width_ * height_; }

  void reset();  // every slot empty, counters zero

  // Pushes e.t into the FIFO of (e.x, e.y, polarity). Events outside the sensor are
  // dropped and counted (out_of_range()), never written out of bounds.
  void update(const Event& e) {
    if (e.x >= width_ || e.y >= height_) {
      ++out_of_range_;
      return;
    }
    std::int64_t* s = fifo(e.x, e.y, e.p ? 0 : 1);
    for (int i = k_ - 1; i > 0; --i) s[i] = s[i - 1];
    s[0] = e.t;
  }
  void update(std::span<const Event> events);  // same, with K specialised

  // Writes volume_size() floats. See the header comment for the two definitions.
  // threads > 1 splits the rows over that many OpenMP threads (1: the calling thread only).
  void readout(std::int64_t t_us, float* out, int threads = 1) const;
  void readout_baldwin(std::int64_t t_us, float* out, BaldwinScale scale = {}, int threads = 1) const;
  // readout() of the pixels inside `rect` (clipped to the sensor) alone: the rest of `out`
  // (volume_size() floats) is left as it was. For a reader that looks only there (stage 2
  // behind a mask), at the rectangle's share of the cost.
  void readout(std::int64_t t_us, float* out, PixelRect rect) const;
  // readout() averaged over d x d cells, written pixel-interleaved: channel c of cell (y, x)
  // to out[(y * out_width + x) * pixel_stride + c] (pixel_stride >= channels()), for the cells
  // inside `cells` (clipped to the whole cells of the sensor) alone; nothing else is written.
  // Bit-identical to readout() and then each cell's values summed (rows, then columns, in
  // order) and scaled by 1 / d^2, without the full-size volume in between.
  void readout_mean(std::int64_t t_us, int d, float* out, int out_width, int pixel_stride, PixelRect cells) const;

  // Raw timestamp of slot k (0 = newest) of a pixel; polarity 1 = ON. kEmpty if none.
  std::int64_t slot(int x, int y, int polarity, int k) const {
    return fifo_[index(x, y, polarity ? 0 : 1) + k];
  }
  std::uint64_t out_of_range() const { return out_of_range_; }

 private:
  std::size_t index(int x, int y, int pol_index) const {
    return ((std::size_t(y) * width_ + x) * 2 + pol_index) * k_;
  }
  std::int64_t* fifo(int x, int y, int pol_index) { return fifo_.data() + index(x, y, pol_index); }

  int width_, height_, k_;
  std::int64_t tau_;
  // [y][x][polarity: 0 = ON, 1 = OFF][slot: 0 = newest]: one event touches one cache line.
  std::vector<std::int64_t> fifo_;
  std::uint64_t out_of_range_ = 0;
};

}  // namespace yelan::camera
