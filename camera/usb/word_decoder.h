// What the DAVIS and DVXplorer decoders share: 16-bit little-endian words split from the
// USB bytes, the 15-bit timestamp words and the wrap words (code 7), the statistics, and
// the sensor size as addressed on the wire (before any axis swap). Each decoder adds its
// own codes (CRTP: Derived::decode_code gets every other word as code and data).
#pragma once
#include <cstdint>
#include <span>
#include <vector>

#include "camera/event.h"
#include "camera/usb/decoder_stats.h"
#include "camera/usb/word_stream.h"

namespace yelan::camera::usb {

template <class Derived>
class WordDecoder {
 public:
  // Decodes `bytes`, appending events to `out`. Any byte sequence is accepted.
  void feed(std::span<const std::uint8_t> bytes, std::vector<Event>& out) {
    stats_.bytes += bytes.size();
    splitter_.split(bytes, [&](std::uint16_t w) { decode_word(w, out); });
  }

  const DecoderStats& stats() const { return stats_; }
  bool has_pending_byte() const { return splitter_.has_pending_byte(); }
  std::int64_t now() const { return clock_.now(); }
  std::uint16_t width() const { return invert_xy_ ? height_ : width_; }
  std::uint16_t height() const { return invert_xy_ ? width_ : height_; }

 protected:
  WordDecoder(std::uint16_t width, std::uint16_t height, bool invert_xy)
      : width_(invert_xy ? height : width), height_(invert_xy ? width : height), invert_xy_(invert_xy) {}

  std::uint16_t width_, height_;  // as addressed on the wire
  bool invert_xy_;
  WordSplitter splitter_;
  TimestampClock clock_;
  DecoderStats stats_;

 private:
  static constexpr std::uint16_t kWrapCode = 7;

  // Bit 15 set: the low 15 bits of the microsecond clock. Else bits 14:12 are a code and
  // bits 11:0 its data; both models send the timestamp wrap as code 7.
  void decode_word(std::uint16_t word, std::vector<Event>& out) {
    ++stats_.words;
    if (word & 0x8000) {
      ++stats_.timestamp_words;
      if (!clock_.on_timestamp(word & 0x7FFF)) ++stats_.non_monotonic;
      return;
    }
    const std::uint16_t code = (word >> 12) & 0x7;
    const std::uint16_t data = word & 0x0FFF;
    if (code == kWrapCode) {
      ++stats_.timestamp_wraps;
      clock_.on_wrap(data);
      return;
    }
    static_cast<Derived*>(this)->decode_code(code, data, out);
  }
};

}  // namespace yelan::camera::usb
