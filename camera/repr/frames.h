// Baseline representations of a window of events (SPEC section 3): event-count frames
// normalised as in DHP19 (used for constant-time and constant-count frames) and a voxel
// grid. All write channel-major float planes (C x H x W) into caller memory. Events
// outside the sensor are skipped and counted in the returned figure.
#pragma once
#include <cstddef>
#include <cstdint>
#include <deque>
#include <span>
#include <vector>

#include "camera/event.h"

namespace yelan::camera {

// Adds one per event to counts[y * width + x] (both polarities). Returns the number of
// events outside the sensor, which are skipped.
std::size_t accumulate_counts(std::span<const Event> events, int width, int height, float* counts);

// DHP19's normalisation, in place: sigma = population standard deviation of the non-zero
// values; each value becomes min(v * 255 / (3 sigma), 255) / 255; zeros stay zero. Like
// DHP19, sigma is floored at 0.1 / 255 (so a frame whose non-zero counts are all equal
// saturates to 1).
void normalize_dhp19(float* frame, std::size_t n);

// Count frame of `events` (all of them: the caller picks the window, e.g. the events in
// (T - 20 ms, T] for a constant-time frame or the last 7500 for a constant-count frame),
// DHP19-normalised. One channel. Returns the out-of-range count.
std::size_t count_frame(std::span<const Event> events, int width, int height, float* out);

// Voxel grid with `bins` channels over [t_begin, t_end]: an event at time t has the
// normalised position u = (bins - 1) (t - t_begin) / (t_end - t_begin) and adds its
// polarity (+1 ON, -1 OFF) times max(0, 1 - |b - u|) to bin b, i.e. split linearly between
// the two nearest bins. Events outside [t_begin, t_end] are clamped to the end bins.
// t_end == t_begin puts everything in bin 0. Zeroes `out` first; returns out-of-range.
std::size_t voxel_grid(std::span<const Event> events, int width, int height, int bins,
                       std::int64_t t_begin, std::int64_t t_end, float* out);

// The recent past of a time-ordered stream, for windowed representations: either the
// events of the last `span_us` (t in (T - span, T]) or the last `count` events. Push events
// in time order; `drop_before(T)` then trims to the window ending at T.
class EventWindow {
 public:
  static EventWindow by_time(std::int64_t span_us);
  static EventWindow by_count(std::size_t count);
  void push(const Event& e);
  void drop_before(std::int64_t t_us);  // by time: keeps t > T - span; by count: no-op
  std::span<const Event> events();      // contiguous view, valid until the next push
  std::size_t size() const { return buf_.size(); }

 private:
  EventWindow(std::int64_t span, std::size_t count) : span_(span), count_(count) {}
  std::int64_t span_;
  std::size_t count_;
  std::deque<Event> buf_;
  std::vector<Event> flat_;
};

}  // namespace yelan::camera
