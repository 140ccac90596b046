#include "camera/usb/decoder_stats.h"

namespace yelan::camera::usb {

std::string DecoderStats::summary() const {
  auto n = [](std::uint64_t v) { return std::to_string(v); };
  return n(bytes) + " bytes, " + n(words) + " words, " + n(events) + " events, " +
         n(timestamp_wraps) + " wraps, " + n(timestamp_resets) + " resets, skipped " +
         n(aps_words) + " frame + " + n(imu_words) + " IMU + " + n(marker_words) +
         " marker words, " + n(warnings()) + " warnings (x out of range " + n(x_out_of_range) +
         ", y out of range " + n(y_out_of_range) + ", x before y " + n(x_before_y) +
         ", unknown " + n(unknown_words) + ", time going back " + n(non_monotonic) + ")";
}

}  // namespace yelan::camera::usb
