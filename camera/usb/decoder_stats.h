// Counters a decoder keeps: what it saw, what it skipped on purpose, and what it had to
// reject (the warnings). A live stream tolerates bad words; they are counted, never fatal.
#pragma once
#include <cstdint>
#include <string>

namespace yelan::camera::usb {

struct DecoderStats {
  std::uint64_t bytes = 0, words = 0, events = 0;
  std::uint64_t timestamp_words = 0, timestamp_wraps = 0, timestamp_resets = 0;
  // Skipped on purpose: frames (APS), IMU samples, external-input and other markers.
  std::uint64_t aps_words = 0, imu_words = 0, marker_words = 0;
  // Warnings: words the protocol does not allow here.
  std::uint64_t x_out_of_range = 0, y_out_of_range = 0, x_before_y = 0, unknown_words = 0,
                non_monotonic = 0;

  std::uint64_t warnings() const {
    return x_out_of_range + y_out_of_range + x_before_y + unknown_words + non_monotonic;
  }
  std::string summary() const;  // one line, for logs and the record command
};

}  // namespace yelan::camera::usb
