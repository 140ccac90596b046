#include "camera/repr/filters.h"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>

namespace yelan::camera {
namespace {

constexpr std::int64_t kNever = std::numeric_limits<std::int64_t>::min();

// t - since, saturating: never overflows for kNever or far-apart stamps.
bool within(std::int64_t t, std::int64_t since, std::int64_t window) {
  return since != kNever && t >= since && t - since <= window;
}

}  // namespace

void check_sensor_size(const char* who, int width, int height) {
  if (width <= 0 || height <= 0 || width > 65536 || height > 65536)
    throw std::invalid_argument(std::string(who) + ": sensor size " + std::to_string(width) + "x" +
                                std::to_string(height) + " is outside 1..65536");
}

HotPixelFilter::HotPixelFilter(int width, int height, std::span<const std::pair<int, int>> hot_xy)
    : PixelFilter("hot pixel filter", width, height) {
  hot_.assign(std::size_t(width) * height, 0);
  for (auto [x, y] : hot_xy) add(x, y);
}

void HotPixelFilter::add(int x, int y) {
  if (x < 0 || y < 0 || x >= width_ || y >= height_)
    throw std::invalid_argument("hot pixel filter: pixel (" + std::to_string(x) + ", " +
                                std::to_string(y) + ") is outside the " + std::to_string(width_) +
                                "x" + std::to_string(height_) + " sensor");
  hot_[std::size_t(y) * width_ + x] = 1;
}

std::size_t HotPixelFilter::hot_count() const {
  return std::size_t(std::count(hot_.begin(), hot_.end(), std::uint8_t{1}));
}

std::vector<std::pair<int, int>> HotPixelFilter::hot_pixels() const {
  std::vector<std::pair<int, int>> out;
  for (std::size_t i = 0; i < hot_.size(); ++i)
    if (hot_[i]) out.emplace_back(int(i % width_), int(i / width_));
  return out;
}

HotPixelFilter HotPixelFilter::learn(std::span<const Event> events, int width, int height,
                                     double ratio, std::size_t min_events) {
  HotPixelFilter f(width, height);
  std::vector<std::uint64_t> counts(std::size_t(width) * height, 0);
  for (const Event& e : events)
    if (e.x < width && e.y < height) ++counts[std::size_t(e.y) * width + e.x];
  std::vector<std::uint64_t> active;
  for (auto c : counts)
    if (c) active.push_back(c);
  if (active.empty()) return f;
  auto mid = active.begin() + active.size() / 2;
  std::nth_element(active.begin(), mid, active.end());
  const double threshold = std::max(ratio * double(*mid), double(min_events) - 0.5);
  for (std::size_t i = 0; i < counts.size(); ++i)
    if (double(counts[i]) > threshold) f.hot_[i] = 1;
  return f;
}

BackgroundActivityFilter::BackgroundActivityFilter(int width, int height, std::int64_t window_us)
    : PixelFilter("background activity filter", width, height), window_(window_us) {
  if (window_us < 0) throw std::invalid_argument("background activity filter: negative window");
  last_.assign(std::size_t(width + 2) * (height + 2), kNever);
}

void BackgroundActivityFilter::reset() {
  std::fill(last_.begin(), last_.end(), kNever);
  out_of_range_ = 0;
}

bool BackgroundActivityFilter::accept(const Event& e) {
  if (outside(e)) return false;
  const std::size_t stride = std::size_t(width_) + 2;
  const std::size_t centre = (std::size_t(e.y) + 1) * stride + e.x + 1;
  bool support = false;
  for (std::size_t row : {centre - stride, centre, centre + stride})
    for (std::size_t i = row - 1; i <= row + 1; ++i)
      if (i != centre && within(e.t, last_[i], window_)) support = true;
  last_[centre] = e.t;
  return support;
}

RefractoryFilter::RefractoryFilter(int width, int height, std::int64_t period_us)
    : PixelFilter("refractory filter", width, height), period_(period_us) {
  if (period_us < 0) throw std::invalid_argument("refractory filter: negative period");
  last_pass_.assign(std::size_t(width) * height, kNever);
}

void RefractoryFilter::reset() {
  std::fill(last_pass_.begin(), last_pass_.end(), kNever);
  out_of_range_ = 0;
}

bool RefractoryFilter::accept(const Event& e) {
  if (outside(e)) return false;
  std::int64_t& last = last_pass_[std::size_t(e.y) * width_ + e.x];
  if (last != kNever && e.t >= last && e.t - last < period_) return false;
  last = e.t;
  return true;
}

}  // namespace yelan::camera
