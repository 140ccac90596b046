// Noise filters on event streams (SPEC section 3). Each is a stateful per-event predicate
// (`accept`) plus `apply`, which compacts a buffer in place and returns how many events
// it kept. Events outside the sensor never pass and are counted.
#pragma once
#include <cstddef>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "camera/event.h"

namespace yelan::camera {

// Drops every event of a fixed set of pixels.
class HotPixelFilter {
 public:
  HotPixelFilter(int width, int height, std::span<const std::pair<int, int>> hot_xy = {});
  // Throws std::invalid_argument for a pixel outside the sensor.
  void add(int x, int y);
  bool is_hot(int x, int y) const {  // false outside the sensor
    return x >= 0 && y >= 0 && x < width_ && y < height_ && hot_[std::size_t(y) * width_ + x] != 0;
  }
  std::size_t hot_count() const;
  std::vector<std::pair<int, int>> hot_pixels() const;  // row-major order

  bool accept(const Event& e) {
    if (e.x >= width_ || e.y >= height_) return ++out_of_range_, false;
    return hot_[std::size_t(e.y) * width_ + e.x] == 0;
  }
  std::size_t apply(std::vector<Event>& events);
  std::uint64_t out_of_range() const { return out_of_range_; }

  // Learns hot pixels from a recording: a pixel is hot when its event count exceeds
  // `ratio` times the median count of the pixels that fired at all, and is at least
  // `min_events` (so a quiet recording with median 1 does not flag pixels with 11 events).
  static HotPixelFilter learn(std::span<const Event> events, int width, int height,
                              double ratio = 10.0, std::size_t min_events = 20);

 private:
  int width_, height_;
  std::vector<std::uint8_t> hot_;
  std::uint64_t out_of_range_ = 0;
};

// Background-activity filter: an event passes when one of its 8 neighbours (not the pixel
// itself, either polarity) had an event at most `window_us` earlier (default 70 ms).
// Every in-range event, passed or not, records its time for its neighbours, as in the
// classic jAER filter; the first event of a region therefore never passes.
class BackgroundActivityFilter {
 public:
  BackgroundActivityFilter(int width, int height, std::int64_t window_us = 70'000);
  bool accept(const Event& e);
  std::size_t apply(std::vector<Event>& events);
  void reset();
  std::uint64_t out_of_range() const { return out_of_range_; }

 private:
  int width_, height_;
  std::int64_t window_;
  std::vector<std::int64_t> last_;  // (width + 2) x (height + 2): a border of never-fired
  std::uint64_t out_of_range_ = 0;
};

// Refractory filter: after a pixel emits an event that passes, further events of that
// pixel (either polarity) are dropped until `period_us` has elapsed (t - t_pass < period).
class RefractoryFilter {
 public:
  RefractoryFilter(int width, int height, std::int64_t period_us);
  bool accept(const Event& e);
  std::size_t apply(std::vector<Event>& events);
  void reset();
  std::uint64_t out_of_range() const { return out_of_range_; }

 private:
  int width_, height_;
  std::int64_t period_;
  std::vector<std::int64_t> last_pass_;
  std::uint64_t out_of_range_ = 0;
};

}  // namespace yelan::camera
