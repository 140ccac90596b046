#include <catch2/catch.hpp>

#include <random>

#include "camera/usb/dvxplorer_decoder.h"
#include "usb_test_util.h"

using yelan::camera::Event;
using yelan::camera::usb::DvxplorerDecoder;
using namespace yelan::test::usb;

namespace {
std::vector<Event> decode(DvxplorerDecoder& d, const std::vector<std::uint16_t>& words) {
  std::vector<Event> out;
  d.feed(bytes(words), out);
  return out;
}
}  // namespace

TEST_CASE("dvxplorer: column, row groups and 8-pixel masks give events (bit 8 clear = ON)", "[usb]") {
  DvxplorerDecoder d;
  CHECK(d.width() == 640);
  CHECK(d.height() == 480);
  auto ev = decode(d, {ts(50), dvx_col(100, true),
                       dvx_groups(2, 3, false),              // group 1 rows 16..23, group 2 rows 40..47
                       dvx_pixels(true, 0b10000001, true),   // rows 16 and 23, ON
                       dvx_pixels(false, 0b00000010, false), // row 41, OFF
                       ts(60), dvx_col(639),
                       dvx_groups(59, 1, true),              // group 1 rows 472..479, group 2 rows 464..471
                       dvx_pixels(true, 0b10000000, false),  // row 479, OFF
                       dvx_pixels(false, 0b00000001, true)}); // row 464, ON
  REQUIRE(ev.size() == 5);
  CHECK(ev[0] == Event{50, 100, 16, 1});
  CHECK(ev[1] == Event{50, 100, 23, 1});
  CHECK(ev[2] == Event{50, 100, 41, 0});
  CHECK(ev[3] == Event{60, 639, 479, 0});
  CHECK(ev[4] == Event{60, 639, 464, 1});
  CHECK(d.frame_starts() == 1);
  CHECK(d.stats().warnings() == 0);
}

TEST_CASE("dvxplorer: timestamps, wraps and resets follow the DAVIS rules", "[usb]") {
  DvxplorerDecoder d;
  auto ev = decode(d, {dvx_col(1), dvx_groups(0, 0, false), ts(7), dvx_pixels(true, 1, true),  // 7
                       wrap(2), dvx_pixels(true, 2, true),                                      // 65536
                       ts(4), dvx_pixels(true, 4, true),                                        // 65540
                       special(1), ts(6), dvx_pixels(true, 8, true)});                          // 65546
  REQUIRE(ev.size() == 4);
  CHECK(ev[0].t == 7);
  CHECK(ev[1].t == 65536);
  CHECK(ev[2].t == 65540);
  CHECK(ev[3].t == 65546);
  CHECK(ev[3].y == 3);
  CHECK(d.stats().timestamp_resets == 1);
}

TEST_CASE("dvxplorer: bad addresses and pixels before any column are warnings, IMU words skipped", "[usb]") {
  DvxplorerDecoder d;
  auto ev = decode(d, {ts(1), dvx_pixels(true, 0xFF, true),  // no column or rows yet: 1 warning
                       dvx_col(640), dvx_col(1023),          // columns beyond 640
                       dvx_col(5), dvx_groups(60, 0, false), // rows 480.. beyond the sensor
                       dvx_groups(1, 2, true),               // group 2 = -1: impossible
                       dvx_groups(3, 0, false),              // fine: rows 24..31
                       special(5), code(5, 0x12), code(5, 0x3AB), special(7),  // IMU
                       dvx_pixels(false, 0x01, true)});      // row 24
  REQUIRE(ev.size() == 1);
  CHECK(ev[0] == Event{1, 5, 24, 1});
  CHECK(d.stats().x_before_y == 1);
  CHECK(d.stats().x_out_of_range == 2);
  CHECK(d.stats().y_out_of_range == 2);
  CHECK(d.stats().imu_words == 4);
}

TEST_CASE("dvxplorer: a stream cut at every byte decodes exactly as the whole stream", "[usb]") {
  std::mt19937 rng(99);
  std::vector<std::uint16_t> w = {ts(0), dvx_col(0), dvx_groups(0, 0, false)};
  std::uint16_t t = 0;
  for (int i = 0; i < 250; ++i) {
    switch (rng() % 5) {
      case 0: t = static_cast<std::uint16_t>(std::min<int>(0x7FFF, t + rng() % 30)); w.push_back(ts(t)); break;
      case 1: w.push_back(dvx_col(rng() % 640, rng() % 10 == 0)); break;
      case 2: w.push_back(dvx_groups(rng() % 30, rng() % 30, false)); break;
      default: w.push_back(dvx_pixels(rng() % 2, static_cast<std::uint8_t>(rng()), rng() % 2)); break;
    }
  }
  const auto data = bytes(w);
  DvxplorerDecoder whole;
  std::vector<Event> ref;
  whole.feed(data, ref);
  REQUIRE(ref.size() > 100);
  for (std::size_t cut = 0; cut <= data.size(); ++cut) {
    DvxplorerDecoder d;
    std::vector<Event> out;
    d.feed(std::span(data).first(cut), out);
    d.feed(std::span(data).subspan(cut), out);
    INFO("cut at byte " << cut);
    REQUIRE(out == ref);
  }
}

TEST_CASE("dvxplorer: random garbage never crashes and stays in the sensor", "[usb]") {
  std::mt19937 rng(4321);
  DvxplorerDecoder d;
  std::vector<Event> out;
  for (int chunk = 0; chunk < 300; ++chunk) {
    std::vector<std::uint8_t> buf(rng() % 3001);
    for (auto& b : buf) b = static_cast<std::uint8_t>(rng());
    d.feed(buf, out);
  }
  CHECK(d.stats().events == out.size());
  CHECK(d.stats().warnings() > 0);
  for (const Event& e : out) {
    REQUIRE(e.x < 640);
    REQUIRE(e.y < 480);
    REQUIRE(e.p <= 1);
  }
}
