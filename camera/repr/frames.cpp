#include "camera/repr/frames.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace yelan::camera {

std::size_t accumulate_counts(std::span<const Event> events, int width, int height, float* counts) {
  std::size_t dropped = 0;
  for (const Event& e : events) {
    if (e.x >= width || e.y >= height) {
      ++dropped;
      continue;
    }
    counts[std::size_t(e.y) * width + e.x] += 1.f;
  }
  return dropped;
}

void normalize_dhp19(float* frame, std::size_t n) {
  double sum = 0, sum_sq = 0;
  std::size_t nonzero = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (frame[i] != 0.f) {
      sum += frame[i];
      sum_sq += double(frame[i]) * frame[i];
      ++nonzero;
    }
  if (nonzero == 0) return;
  const double mean = sum / nonzero;
  const double sigma = std::max(std::sqrt(std::max(sum_sq / nonzero - mean * mean, 0.0)), 0.1 / 255);
  const double scale = 1.0 / (3 * sigma);  // 255 / (3 sigma), then / 255
  for (std::size_t i = 0; i < n; ++i)
    if (frame[i] != 0.f) frame[i] = static_cast<float>(std::min(frame[i] * scale, 1.0));
}

std::size_t count_frame(std::span<const Event> events, int width, int height, float* out) {
  const std::size_t n = std::size_t(width) * height;
  std::fill(out, out + n, 0.f);
  const std::size_t dropped = accumulate_counts(events, width, height, out);
  normalize_dhp19(out, n);
  return dropped;
}

std::size_t voxel_grid(std::span<const Event> events, int width, int height, int bins,
                       std::int64_t t_begin, std::int64_t t_end, float* out) {
  if (bins < 1) throw std::invalid_argument("voxel grid: bins must be >= 1");
  if (t_end < t_begin) throw std::invalid_argument("voxel grid: t_end < t_begin");
  const std::size_t plane = std::size_t(width) * height;
  std::fill(out, out + plane * bins, 0.f);
  const double span = double(t_end - t_begin);
  std::size_t dropped = 0;
  for (const Event& e : events) {
    if (e.x >= width || e.y >= height) {
      ++dropped;
      continue;
    }
    const double u = span > 0 ? std::clamp(double(e.t - t_begin) / span, 0.0, 1.0) * (bins - 1) : 0.0;
    const int lo = std::min(int(u), bins - 1);
    const float frac = static_cast<float>(u - lo);
    const float pol = e.p ? 1.f : -1.f;
    const std::size_t pix = std::size_t(e.y) * width + e.x;
    out[lo * plane + pix] += pol * (1.f - frac);
    if (lo + 1 < bins) out[(lo + 1) * plane + pix] += pol * frac;
  }
  return dropped;
}

EventWindow EventWindow::by_time(std::int64_t span_us) {
  if (span_us <= 0) throw std::invalid_argument("event window: span must be positive");
  return EventWindow(span_us, 0);
}

EventWindow EventWindow::by_count(std::size_t count) {
  if (count == 0) throw std::invalid_argument("event window: count must be positive");
  return EventWindow(0, count);
}

void EventWindow::push(const Event& e) {
  buf_.push_back(e);
  if (count_ && buf_.size() > count_) buf_.pop_front();
}

void EventWindow::drop_before(std::int64_t t_us) {
  if (count_) return;
  while (!buf_.empty() && buf_.front().t <= t_us - span_) buf_.pop_front();
}

std::span<const Event> EventWindow::events() {
  flat_.assign(buf_.begin(), buf_.end());
  return flat_;
}

}  // namespace yelan::camera
