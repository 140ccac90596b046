// Decodes the DVXplorer USB event stream. Same 16-bit word framing, timestamps, wraps,
// resets and special events as DAVIS, but pixels arrive as a column address followed by
// 8-pixel groups (README.md has the word table). IMU words are skipped.
#pragma once
#include <span>
#include <vector>

#include "camera/event.h"
#include "camera/usb/decoder_stats.h"
#include "camera/usb/word_stream.h"

namespace yelan::camera::usb {

class DvxplorerDecoder {
 public:
  explicit DvxplorerDecoder(std::uint16_t width = 640, std::uint16_t height = 480, bool invert_xy = false);

  void feed(std::span<const std::uint8_t> bytes, std::vector<Event>& out);
  void decode_word(std::uint16_t word, std::vector<Event>& out);

  const DecoderStats& stats() const { return stats_; }
  bool has_pending_byte() const { return splitter_.has_pending_byte(); }
  std::int64_t now() const { return clock_.now(); }
  std::uint16_t width() const { return invert_xy_ ? height_ : width_; }
  std::uint16_t height() const { return invert_xy_ ? width_ : height_; }
  std::uint64_t frame_starts() const { return frame_starts_; }

 private:
  void group(std::uint16_t data, int base_y, std::vector<Event>& out);

  std::uint16_t width_, height_;  // as addressed on the wire
  bool invert_xy_;
  WordSplitter splitter_;
  TimestampClock clock_;
  DecoderStats stats_;
  int last_x_ = -1, group1_y_ = -1, group2_y_ = -1;
  std::uint64_t frame_starts_ = 0;
};

}  // namespace yelan::camera::usb
