// Builders of DAVIS and DVXplorer USB words for the camera_usb tests.
#pragma once
#include <cstdint>
#include <initializer_list>
#include <vector>

namespace yelan::test::usb {

inline std::uint16_t ts(std::uint16_t low15) { return static_cast<std::uint16_t>(0x8000 | (low15 & 0x7FFF)); }
inline std::uint16_t wrap(std::uint16_t n) { return static_cast<std::uint16_t>(0x7000 | (n & 0x0FFF)); }
inline std::uint16_t special(std::uint16_t d) { return d & 0x0FFF; }
inline std::uint16_t code(std::uint16_t c, std::uint16_t data) {
  return static_cast<std::uint16_t>((c << 12) | (data & 0x0FFF));
}
// DAVIS: row, then column with polarity.
inline std::uint16_t row(std::uint16_t y) { return code(1, y); }
inline std::uint16_t col(std::uint16_t x, bool on) { return code(on ? 3 : 2, x); }
// DVXplorer: column (optionally start of frame), row groups, 8-pixel groups.
inline std::uint16_t dvx_col(std::uint16_t x, bool frame_start = false) {
  return code(1, static_cast<std::uint16_t>(x | (frame_start ? 0x0800 : 0)));
}
inline std::uint16_t dvx_groups(std::uint16_t g1, std::uint16_t offset, bool minus) {
  return code(4, static_cast<std::uint16_t>(g1 | (offset << 6) | (minus ? 0x0800 : 0)));
}
inline std::uint16_t dvx_pixels(bool group1, std::uint8_t mask, bool on) {
  return code(group1 ? 3 : 2, static_cast<std::uint16_t>(mask | (on ? 0 : 0x0100)));
}

inline std::vector<std::uint8_t> bytes(const std::vector<std::uint16_t>& words) {
  std::vector<std::uint8_t> b;
  for (std::uint16_t w : words) {
    b.push_back(static_cast<std::uint8_t>(w & 0xFF));
    b.push_back(static_cast<std::uint8_t>(w >> 8));
  }
  return b;
}

}  // namespace yelan::test::usb
