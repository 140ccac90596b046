// Decodes the DAVIS USB event stream (16-bit little-endian words; README.md has the word
// table) into polarity events. Frames (APS) and IMU samples are recognised and skipped.
#pragma once
#include <span>
#include <vector>

#include "camera/event.h"
#include "camera/usb/decoder_stats.h"
#include "camera/usb/word_stream.h"

namespace yelan::camera::usb {

class DavisDecoder {
 public:
  // width x height of the DVS array as the device reports it (DAVIS346: 346 x 260);
  // invert_xy swaps the two axes (DVS orientation bit 2) for rotated sensors.
  explicit DavisDecoder(std::uint16_t width = 346, std::uint16_t height = 260, bool invert_xy = false);

  // Decodes `bytes`, appending events to `out`. Any byte sequence is accepted.
  void feed(std::span<const std::uint8_t> bytes, std::vector<Event>& out);
  void decode_word(std::uint16_t word, std::vector<Event>& out);

  const DecoderStats& stats() const { return stats_; }
  bool has_pending_byte() const { return splitter_.has_pending_byte(); }
  std::int64_t now() const { return clock_.now(); }
  std::uint16_t width() const { return invert_xy_ ? height_ : width_; }
  std::uint16_t height() const { return invert_xy_ ? width_ : height_; }

 private:
  void special(std::uint16_t data);

  std::uint16_t width_, height_;  // as addressed on the wire (before any axis swap)
  bool invert_xy_;
  WordSplitter splitter_;
  TimestampClock clock_;
  DecoderStats stats_;
  int last_y_ = -1;  // row address of the events that follow; -1 before the first one
};

}  // namespace yelan::camera::usb
