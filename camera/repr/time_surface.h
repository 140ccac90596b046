// Time surface: per pixel and polarity the timestamp of the last event, read out at time
// T as exp(-(T - t_last) / tau). Two channels (ON, OFF), channel-major. An empty pixel or
// an event newer than T (not yet arrived) reads 0. Update O(1), read-out O(pixels).
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "camera/event.h"

namespace yelan::camera {

class TimeSurface {
 public:
  // Throws std::invalid_argument for a non-positive size or tau.
  TimeSurface(int width, int height, std::int64_t tau_us = 50'000);

  int width() const { return width_; }
  int height() const { return height_; }
  static constexpr int channels() { return 2; }
  std::size_t volume_size() const { return 2 * std::size_t(width_) * height_; }

  void update(const Event& e) {
    if (e.x >= width_ || e.y >= height_) {
      ++out_of_range_;
      return;
    }
    last_[(e.p ? 0 : plane_) + std::size_t(e.y) * width_ + e.x] = e.t;
  }
  void update(std::span<const Event> events) {
    for (const Event& e : events) update(e);
  }
  void readout(std::int64_t t_us, float* out) const;
  void reset();
  std::uint64_t out_of_range() const { return out_of_range_; }

 private:
  int width_, height_;
  std::size_t plane_;
  std::int64_t tau_;
  std::vector<std::int64_t> last_;  // [polarity: ON, OFF][y][x]; kNever when empty
  std::uint64_t out_of_range_ = 0;
};

}  // namespace yelan::camera
