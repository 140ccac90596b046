#include "camera/usb/dvxplorer_decoder.h"

namespace yelan::camera::usb {

DvxplorerDecoder::DvxplorerDecoder(std::uint16_t width, std::uint16_t height, bool invert_xy)
    : WordDecoder(width, height, invert_xy) {}

void DvxplorerDecoder::decode_code(std::uint16_t code, std::uint16_t data, std::vector<Event>& out) {
  switch (code) {
    case 0:  // special events: same numbering as DAVIS, without the frame markers
      switch (data) {
        case 1:
          ++stats_.timestamp_resets;
          clock_.on_reset();
          return;
        case 5:
        case 7:
          ++stats_.imu_words;
          return;
        case 2: case 3: case 4: case 16: case 17:
          ++stats_.marker_words;
          return;
        default:
          ++stats_.unknown_words;
          return;
      }
    case 1: {  // column: address in bits 9:0, bit 11 marks the start of a readout frame
      if (data & 0x0800) ++frame_starts_;
      const std::uint16_t x = data & 0x03FF;
      if (x >= width_) {
        ++stats_.x_out_of_range;
        return;
      }
      last_x_ = x;
      return;
    }
    case 2:  // 8-pixel group of row group 2
      group(data, group2_y_, out);
      return;
    case 3:  // 8-pixel group of row group 1
      group(data, group1_y_, out);
      return;
    case 4: {  // row groups: group 1 in bits 5:0, group 2 = group 1 -/+ bits 10:6 (bit 11 = minus)
      const int g1 = data & 0x3F;
      const int offset = (data >> 6) & 0x1F;
      const int g2 = (data & 0x0800) ? g1 - offset : g1 + offset;
      if (g1 * 8 >= height_ || g2 < 0 || g2 * 8 >= height_) {
        ++stats_.y_out_of_range;
        return;
      }
      group1_y_ = g1 * 8;
      group2_y_ = g2 * 8;
      return;
    }
    case 5:  // IMU bytes and scale
      ++((((data >> 8) & 0xF) == 0 || ((data >> 8) & 0xF) == 3) ? stats_.imu_words : stats_.unknown_words);
      return;
    case 6:
      ++stats_.unknown_words;
      return;
  }
}

// Bits 7:0 say which of the 8 rows base_y..base_y+7 fired; bit 8 clear means ON.
void DvxplorerDecoder::group(std::uint16_t data, int base_y, std::vector<Event>& out) {
  if (last_x_ < 0 || base_y < 0) {
    ++stats_.x_before_y;
    return;
  }
  const std::uint8_t polarity = (data & 0x0100) ? 0 : 1;
  for (int i = 0; i < 8; ++i) {
    if (!(data & (1u << i))) continue;
    const int y = base_y + i;
    if (y >= height_) {
      ++stats_.y_out_of_range;
      continue;
    }
    std::uint16_t ex = static_cast<std::uint16_t>(last_x_), ey = static_cast<std::uint16_t>(y);
    if (invert_xy_) std::swap(ex, ey);
    out.push_back({clock_.now(), ex, ey, polarity});
    ++stats_.events;
  }
}

}  // namespace yelan::camera::usb
