// Decodes the DAVIS USB event stream (16-bit little-endian words; README.md has the word
// table) into polarity events. Frames (APS) and IMU samples are recognised and skipped.
#pragma once
#include <cstdint>
#include <vector>

#include "camera/usb/word_decoder.h"

namespace yelan::camera::usb {

class DavisDecoder : public WordDecoder<DavisDecoder> {
 public:
  // width x height of the DVS array as the device reports it (DAVIS346: 346 x 260);
  // invert_xy swaps the two axes (DVS orientation bit 2) for rotated sensors.
  explicit DavisDecoder(std::uint16_t width = 346, std::uint16_t height = 260, bool invert_xy = false);

 private:
  friend class WordDecoder<DavisDecoder>;  // the framing hands it every word but timestamps and wraps
  void decode_code(std::uint16_t code, std::uint16_t data, std::vector<Event>& out);
  void special(std::uint16_t data);

  int last_y_ = -1;  // row address of the events that follow; -1 before the first one
};

}  // namespace yelan::camera::usb
