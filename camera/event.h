// One event of a dynamic vision sensor (SPEC section 2).
#pragma once
#include <cstdint>

namespace yelan::camera {

struct Event {
  std::int64_t t;       // microseconds; non-decreasing within a stream (within tolerance)
  std::uint16_t x, y;   // pixel, origin top-left
  std::uint8_t p;       // polarity: 1 = ON (brighter), 0 = OFF
};

inline bool operator==(const Event& a, const Event& b) {
  return a.t == b.t && a.x == b.x && a.y == b.y && a.p == b.p;
}

}  // namespace yelan::camera
