// Decodes the DVXplorer USB event stream. Same 16-bit word framing, timestamps, wraps,
// resets and special events as DAVIS, but pixels arrive as a column address followed by
// 8-pixel groups (README.md has the word table). IMU words are skipped.
#pragma once
#include <cstdint>
#include <vector>

#include "camera/usb/word_decoder.h"

namespace yelan::camera::usb {

class DvxplorerDecoder : public WordDecoder<DvxplorerDecoder> {
 public:
  explicit DvxplorerDecoder(std::uint16_t width = 640, std::uint16_t height = 480, bool invert_xy = false);

  std::uint64_t frame_starts() const { return frame_starts_; }

 private:
  friend class WordDecoder<DvxplorerDecoder>;  // the framing hands it every word but timestamps and wraps
  void decode_code(std::uint16_t code, std::uint16_t data, std::vector<Event>& out);
  void group(std::uint16_t data, int base_y, std::vector<Event>& out);

  int last_x_ = -1, group1_y_ = -1, group2_y_ = -1;
  std::uint64_t frame_starts_ = 0;
};

}  // namespace yelan::camera::usb
