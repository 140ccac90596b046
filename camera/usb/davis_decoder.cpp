#include "camera/usb/davis_decoder.h"

namespace yelan::camera::usb {
namespace {

// Word codes, bits 14:12 of a word whose bit 15 is clear (7, the wrap, is WordDecoder's).
enum Code : std::uint16_t {
  kSpecial = 0, kRow = 1, kColumnOff = 2, kColumnOn = 3, kApsSample = 4, kMisc8 = 5, kMisc10 = 6
};

// Special events (code 0), by their 12-bit data.
enum Special : std::uint16_t {
  kReserved = 0, kTimestampReset = 1, kExtFalling = 2, kExtRising = 3, kExtPulse = 4,
  kImuStart = 5, kImuEnd = 7, kFrameStartGlobal = 8, kFrameStartRolling = 9, kFrameEnd = 10,
  kResetColumnStart = 11, kSignalColumnStart = 12, kColumnEnd = 13, kExposureStart = 14,
  kExposureEnd = 15, kGeneratorFalling = 16, kGeneratorRising = 17
};

}  // namespace

DavisDecoder::DavisDecoder(std::uint16_t width, std::uint16_t height, bool invert_xy)
    : WordDecoder(width, height, invert_xy) {}

void DavisDecoder::decode_code(std::uint16_t code, std::uint16_t data, std::vector<Event>& out) {
  switch (code) {
    case kSpecial:
      special(data);
      return;
    case kRow:
      if (data >= height_) {
        ++stats_.y_out_of_range;  // keep the previous row: the next columns are suspect anyway
        return;
      }
      last_y_ = data;
      return;
    case kColumnOff:
    case kColumnOn: {
      if (data >= width_) {
        ++stats_.x_out_of_range;
        return;
      }
      if (last_y_ < 0) {
        ++stats_.x_before_y;
        return;
      }
      std::uint16_t x = data, y = static_cast<std::uint16_t>(last_y_);
      if (invert_xy_) std::swap(x, y);
      out.push_back({clock_.now(), x, y, static_cast<std::uint8_t>(code == kColumnOn ? 1 : 0)});
      ++stats_.events;
      return;
    }
    case kApsSample:
      ++stats_.aps_words;
      return;
    case kMisc10:  // sub-code 0 (bits 11:10): frame exposure value, 10 bits at a time
      ++(((data >> 10) & 0x3) == 0 ? stats_.aps_words : stats_.unknown_words);
      return;
    case kMisc8: {  // sub-code (bits 11:8): 0 IMU byte, 1-2 frame region, 3 IMU scale
      const std::uint16_t sub = (data >> 8) & 0xF;
      ++(sub == 0 || sub == 3 ? stats_.imu_words : sub <= 2 ? stats_.aps_words : stats_.unknown_words);
      return;
    }
  }
}

void DavisDecoder::special(std::uint16_t data) {
  switch (data) {
    case kTimestampReset:
      ++stats_.timestamp_resets;
      clock_.on_reset();
      return;
    case kImuStart:
    case kImuEnd:
      ++stats_.imu_words;
      return;
    case kFrameStartGlobal:
    case kFrameStartRolling:
    case kFrameEnd:
    case kResetColumnStart:
    case kSignalColumnStart:
    case kColumnEnd:
    case kExposureStart:
    case kExposureEnd:
      ++stats_.aps_words;
      return;
    case kExtFalling:
    case kExtRising:
    case kExtPulse:
    case kGeneratorFalling:
    case kGeneratorRising:
      ++stats_.marker_words;
      return;
    default:  // 0 is reserved; 6 and 18..4095 are not defined
      ++stats_.unknown_words;
      return;
  }
}

}  // namespace yelan::camera::usb
