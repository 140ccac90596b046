// A dancer recording's true masks over a span, looked up by tick: what the deployed masks
// are scored against (bench early-exit's sweeps, eval --run's IoU as deployed).
#pragma once
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "camera/sim/recording_reader.h"

namespace yelan::run {

struct TrueMasks {
  camera::sim::RecordingInfo info;
  std::int64_t t0 = 0, end = 0;  // the span, microseconds on the recording's clock
  std::size_t m0 = 0, m1 = 0;    // its mask indices (into info.mask_t), [m0, m1)
  std::vector<std::uint8_t> masks;

  // [skip_s, skip_s + seconds] after the first event; nothing read for a recording without a dancer.
  TrueMasks(const std::string& path, double seconds, double skip_s);
  // The index (into info.mask_t) of the true mask at tick t_us, within a millisecond (ticks
  // on the recording's clock sit on the mask times); none outside the span.
  std::optional<std::size_t> index_at(std::int64_t t_us) const;
  const std::uint8_t* mask(std::size_t index) const;
};

}  // namespace yelan::run
