// A dancer recording's true masks over a span, looked up by tick: what the deployed masks
// are scored against (bench early-exit's sweeps, eval --run's IoU as deployed).
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "camera/sim/recording_reader.h"

namespace yelan::run {

// The index in [from, to) of the time in times (ascending) within a millisecond of t_us: ticks
// on a mask clock sit on its times. None where no time is that close.
std::optional<std::size_t> mask_index_near(const std::vector<std::int64_t>& times, std::size_t from, std::size_t to,
                                           std::int64_t t_us);

struct TrueMasks {
  camera::sim::RecordingInfo info;
  std::int64_t t0 = 0, end = 0;  // the span, microseconds on the recording's clock
  std::size_t m0 = 0, m1 = 0;    // its mask indices (into info.mask_t), [m0, m1)
  std::vector<std::uint8_t> masks;
  std::vector<std::uint8_t> shows;  // per mask of the span: any pixel of the dancer
  bool truncated = false;           // the file held fewer pictures than mask times

  // [skip_s, skip_s + seconds] after the first event; nothing read for a recording without a dancer.
  TrueMasks(const std::string& path, double seconds, double skip_s);
  // The index (into info.mask_t) of the true mask at tick t_us, within a millisecond (ticks
  // on the recording's clock sit on the mask times); none outside the span.
  std::optional<std::size_t> index_at(std::int64_t t_us) const;
  const std::uint8_t* mask(std::size_t index) const;
  // Whether any pixel of the dancer shows at t_us: the latest mask of the span at or before it
  // (the span's first before it: ticks on the mask clock start on a mask); true where the span
  // holds no mask, or past the last picture of a truncated file (no opinion).
  bool shows_at(std::int64_t t_us) const;
};

}  // namespace yelan::run
