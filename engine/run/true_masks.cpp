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
  if (pixels && masks.size() / pixels < m1 - m0) {
    m1 = m0 + masks.size() / pixels;
    truncated = true;
  }
  for (std::size_t k = m0; k < m1; ++k) {
    const std::uint8_t* m = mask(k);
    shows.push_back(std::any_of(m, m + pixels, [](std::uint8_t v) { return v != 0; }));
  }
}

std::optional<std::size_t> mask_index_near(const std::vector<std::int64_t>& times, std::size_t from, std::size_t to,
                                           std::int64_t t_us) {
  const auto b = times.begin();
  const auto it = std::lower_bound(b + std::ptrdiff_t(from), b + std::ptrdiff_t(to), t_us - 1000);
  if (it == b + std::ptrdiff_t(to) || std::llabs(*it - t_us) > 1000) return std::nullopt;
  return std::size_t(it - b);
}

std::optional<std::size_t> TrueMasks::index_at(std::int64_t t_us) const { return mask_index_near(info.mask_t, m0, m1, t_us); }

bool TrueMasks::shows_at(std::int64_t t_us) const {
  if (m1 <= m0 || (truncated && t_us > info.mask_t[m1 - 1] + 1000)) return true;
  const auto b = info.mask_t.begin();
  const auto it = std::upper_bound(b + std::ptrdiff_t(m0), b + std::ptrdiff_t(m1), t_us);
  const std::size_t k = it == b + std::ptrdiff_t(m0) ? m0 : std::size_t(it - b) - 1;
  return shows[k - m0] != 0;
}

const std::uint8_t* TrueMasks::mask(std::size_t index) const {
  return &masks[(index - m0) * std::size_t(info.camera.width) * std::size_t(info.camera.height)];
}

}  // namespace yelan::run
