#include "engine/run/true_masks.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

namespace yelan::run {

TrueMasks::TrueMasks(const std::string& path, double seconds, double skip_s) : info(camera::sim::read_recording_info(path)) {
  if (!info.dancer) return;
  t0 = info.first_event_us + std::llround(skip_s * 1e6);
  end = info.first_event_us + std::llround((skip_s + seconds) * 1e6);
  m0 = std::size_t(std::lower_bound(info.mask_t.begin(), info.mask_t.end(), t0) - info.mask_t.begin());
  m1 = std::size_t(std::upper_bound(info.mask_t.begin(), info.mask_t.end(), end) - info.mask_t.begin());
  masks = camera::sim::read_recording_masks(path, m0, m1 - m0);
  // Fewer pictures than times (a truncated file): the span ends where the pictures do.
  const std::size_t pixels = std::size_t(info.camera.width) * std::size_t(info.camera.height);
  if (pixels && masks.size() / pixels < m1 - m0) m1 = m0 + masks.size() / pixels;
}

std::optional<std::size_t> TrueMasks::index_at(std::int64_t t_us) const {
  const auto b = info.mask_t.begin();
  const auto it = std::lower_bound(b + std::ptrdiff_t(m0), b + std::ptrdiff_t(m1), t_us - 1000);
  if (it == b + std::ptrdiff_t(m1) || std::llabs(*it - t_us) > 1000) return std::nullopt;
  return std::size_t(it - b);
}

const std::uint8_t* TrueMasks::mask(std::size_t index) const {
  return &masks[(index - m0) * std::size_t(info.camera.width) * std::size_t(info.camera.height)];
}

}  // namespace yelan::run
