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

// Throws std::invalid_argument naming `who` unless the size is within 1..65536.
void check_sensor_size(const char* who, int width, int height);

// What every filter shares: the sensor's bounds, the count of events outside them, and
// apply(), which keeps the events Self::accept passes, in order (CRTP: accept inlines).
template <class Self>
class PixelFilter {
 public:
  std::size_t apply(std::vector<Event>& events) {
    std::size_t kept = 0;
    for (const Event& e : events)
      if (static_cast<Self&>(*this).accept(e)) events[kept++] = e;
    events.resize(kept);
    return kept;
  }
  std::uint64_t out_of_range() const { return out_of_range_; }

 protected:
  PixelFilter(const char* who, int width, int height) : width_(width), height_(height) {
    check_sensor_size(who, width, height);
  }
  bool outside(const Event& e) { return (e.x >= width_ || e.y >= height_) && (++out_of_range_, true); }

  int width_, height_;
  std::uint64_t out_of_range_ = 0;
};

// Drops every event of a fixed set of pixels.
class HotPixelFilter : public PixelFilter<HotPixelFilter> {
 public:
  HotPixelFilter(int width, int height, std::span<const std::pair<int, int>> hot_xy = {});
  // Throws std::invalid_argument for a pixel outside the sensor.
  void add(int x, int y);
  bool is_hot(int x, int y) const {  // false outside the sensor
    return x >= 0 && y >= 0 && x < width_ && y < height_ && hot_[std::size_t(y) * width_ + x] != 0;
  }
  std::size_t hot_count() const;
  std::vector<std::pair<int, int>> hot_pixels() const;  // row-major order

  bool accept(const Event& e) { return !outside(e) && hot_[std::size_t(e.y) * width_ + e.x] == 0; }

  // Learns hot pixels from a recording: a pixel is hot when its event count exceeds
  // `ratio` times the median count of the pixels that fired at all, and is at least
  // `min_events` (so a quiet recording with median 1 does not flag pixels with 11 events).
  static HotPixelFilter learn(std::span<const Event> events, int width, int height,
                              double ratio = 10.0, std::size_t min_events = 20);

 private:
  std::vector<std::uint8_t> hot_;
};

// Background-activity filter: an event passes when one of its 8 neighbours (not the pixel
// itself, either polarity) had an event at most `window_us` earlier (default 70 ms).
// Every in-range event, passed or not, records its time for its neighbours, as in the
// classic jAER filter; the first event of a region therefore never passes.
class BackgroundActivityFilter : public PixelFilter<BackgroundActivityFilter> {
 public:
  BackgroundActivityFilter(int width, int height, std::int64_t window_us = 70'000);
  bool accept(const Event& e);
  void reset();

 private:
  std::int64_t window_;
  std::vector<std::int64_t> last_;  // (width + 2) x (height + 2): a border of never-fired
};

// Refractory filter: after a pixel emits an event that passes, further events of that
// pixel (either polarity) are dropped until `period_us` has elapsed (t - t_pass < period).
class RefractoryFilter : public PixelFilter<RefractoryFilter> {
 public:
  RefractoryFilter(int width, int height, std::int64_t period_us);
  bool accept(const Event& e);
  void reset();

 private:
  std::int64_t period_;
  std::vector<std::int64_t> last_pass_;
};

}  // namespace yelan::camera
