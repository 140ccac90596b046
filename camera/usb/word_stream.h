// Pieces shared by the DAVIS and DVXplorer decoders: splitting USB buffers into 16-bit
// little-endian words (a buffer may end mid-word: the odd byte waits for the next buffer)
// and rebuilding 64-bit microsecond timestamps from 15-bit stamps, wraps and resets.
#pragma once
#include <cstdint>
#include <optional>
#include <span>

namespace yelan::camera::usb {

class WordSplitter {
 public:
  // Calls fn(word) for every complete word of `bytes`, in order.
  template <class Fn>
  void split(std::span<const std::uint8_t> bytes, Fn&& fn) {
    std::size_t i = 0;
    if (pending_ && !bytes.empty()) {
      fn(static_cast<std::uint16_t>(*pending_ | (bytes[0] << 8)));
      pending_.reset();
      i = 1;
    }
    for (; i + 1 < bytes.size(); i += 2) fn(static_cast<std::uint16_t>(bytes[i] | (bytes[i + 1] << 8)));
    if (i < bytes.size()) pending_ = bytes[i];
  }
  bool has_pending_byte() const { return pending_.has_value(); }
  void reset() { pending_.reset(); }

 private:
  std::optional<std::uint8_t> pending_;
};

// Device time = wrap_base + low 15 bits; a wrap word adds count * 2^15 us; a reset word
// restarts device time at 0. Host time continues across resets from the last timestamp
// seen (offset_), so the output never jumps backwards because of a reset.
class TimestampClock {
 public:
  static constexpr std::int64_t kWrapStep = 0x8000;  // 2^15 us per wrap

  // Returns false when the new time is below the previous one (a non-monotonic stamp).
  bool on_timestamp(std::uint16_t low15) {
    const std::int64_t next = wrap_base_ + (low15 & 0x7FFF);
    const bool monotonic = next >= device_now_;
    device_now_ = next;
    return monotonic;
  }
  void on_wrap(std::uint16_t count) {
    wrap_base_ += kWrapStep * count;
    device_now_ = wrap_base_;
  }
  void on_reset() {
    offset_ = now();
    wrap_base_ = 0;
    device_now_ = 0;
  }
  std::int64_t now() const { return offset_ + device_now_; }

 private:
  std::int64_t offset_ = 0, wrap_base_ = 0, device_now_ = 0;
};

}  // namespace yelan::camera::usb
