#include <catch2/catch.hpp>

#include <random>

#include "camera/usb/davis_decoder.h"
#include "usb_test_util.h"

using yelan::camera::Event;
using yelan::camera::usb::DavisDecoder;
using namespace yelan::test::usb;

namespace {
std::vector<Event> decode(DavisDecoder& d, const std::vector<std::uint16_t>& words) {
  std::vector<Event> out;
  d.feed(bytes(words), out);
  return out;
}
}  // namespace

TEST_CASE("davis: a row then columns give events at the current timestamp, code 3 = ON", "[usb]") {
  DavisDecoder d;
  auto ev = decode(d, {ts(100), row(5), col(10, true), col(11, false), ts(200), row(259), col(345, true), col(0, false)});
  REQUIRE(ev.size() == 4);
  CHECK(ev[0] == Event{100, 10, 5, 1});
  CHECK(ev[1] == Event{100, 11, 5, 0});
  CHECK(ev[2] == Event{200, 345, 259, 1});
  CHECK(ev[3] == Event{200, 0, 259, 0});
  CHECK(d.stats().events == 4);
  CHECK(d.stats().words == 8);
  CHECK(d.stats().timestamp_words == 2);
  CHECK(d.stats().warnings() == 0);
  CHECK(d.width() == 346);
  CHECK(d.height() == 260);
}

TEST_CASE("davis: a wrap word adds count x 2^15 us and sets time to the wrap point", "[usb]") {
  DavisDecoder d;
  auto ev = decode(d, {row(1), ts(0x7FFF), col(1, true),   // 32767
                       wrap(1), col(2, true),               // 32768
                       ts(5), col(3, true),                 // 32768 + 5
                       wrap(3), ts(1), col(4, true),        // 4 * 32768 + 1
                       wrap(4095), ts(0x7FFF), col(5, true)});  // (4 + 4095) * 32768 + 32767
  REQUIRE(ev.size() == 5);
  CHECK(ev[0].t == 32767);
  CHECK(ev[1].t == 32768);
  CHECK(ev[2].t == 32773);
  CHECK(ev[3].t == 131073);
  CHECK(ev[4].t == 4099LL * 32768 + 32767);  // beyond 2^27 us: no 32-bit overflow
  CHECK(d.stats().timestamp_wraps == 3);
  CHECK(d.stats().non_monotonic == 0);
}

TEST_CASE("davis: a timestamp reset restarts device time and host time continues from there", "[usb]") {
  DavisDecoder d;
  auto ev = decode(d, {row(7), wrap(2), ts(10), col(1, false),  // 65546
                       special(1),                              // reset
                       ts(3), col(2, true),                     // 65546 + 3
                       wrap(1), ts(0), col(3, true)});          // 65546 + 32768
  REQUIRE(ev.size() == 3);
  CHECK(ev[0].t == 65546);
  CHECK(ev[1].t == 65549);
  CHECK(ev[2].t == 65546 + 32768);
  CHECK(d.stats().timestamp_resets == 1);
  CHECK(d.stats().non_monotonic == 0);
  CHECK(d.stats().warnings() == 0);
}

TEST_CASE("davis: IMU, frame and external-input words are skipped and counted", "[usb]") {
  DavisDecoder d;
  std::vector<std::uint16_t> w = {ts(1), row(2), col(3, true)};
  w.push_back(special(5));                                     // IMU start
  w.push_back(code(5, 0x300 | 0x6B));                          // IMU scale config
  for (int i = 0; i < 14; ++i) w.push_back(code(5, i * 7));    // 14 IMU data bytes
  w.push_back(special(7));                                     // IMU end
  w.push_back(col(4, false));                                  // DVS still flows in between
  w.push_back(code(5, 0x100 | 0x01));                          // APS ROI, part 1
  w.push_back(code(5, 0x200 | 0x02));                          // APS ROI, part 2
  w.push_back(special(9));                                     // rolling-shutter frame start
  w.push_back(special(14));                                    // exposure start
  w.push_back(special(15));                                    // exposure end
  w.push_back(special(11));                                    // reset column start
  for (int i = 0; i < 5; ++i) w.push_back(code(4, 600 + i));   // ADC samples
  w.push_back(special(13));                                    // column end
  w.push_back(special(12));                                    // signal column start
  w.push_back(code(4, 900));
  w.push_back(special(13));
  w.push_back(code(6, 0x3FF));                                 // exposure value (misc10)
  w.push_back(special(10));                                    // frame end
  w.push_back(special(8));                                     // global-shutter frame start
  for (std::uint16_t m : {2, 3, 4, 16, 17}) w.push_back(special(m));  // external input/generator
  w.push_back(ts(9));
  w.push_back(col(5, true));
  auto ev = decode(d, w);
  REQUIRE(ev.size() == 3);
  CHECK(ev[1] == Event{1, 4, 2, 0});
  CHECK(ev[2] == Event{9, 5, 2, 1});
  CHECK(d.stats().imu_words == 17);
  CHECK(d.stats().aps_words == 2 + 6 + 5 + 1 + 1 + 2 + 1);
  CHECK(d.stats().marker_words == 5);
  CHECK(d.stats().warnings() == 0);
}

TEST_CASE("davis: impossible words are counted as warnings, never turned into events", "[usb]") {
  DavisDecoder d;
  auto ev = decode(d, {ts(10), col(3, true),        // column before any row
                       row(260), row(4095),         // rows beyond 260
                       row(8), col(346, true),      // column beyond 346
                       col(345, false),             // fine
                       special(0), special(6), special(18), special(4095),  // reserved/undefined
                       code(5, 0x400), code(5, 0xF00), code(6, 0x400),     // undefined sub-codes
                       ts(500), ts(400), col(1, true)});                    // time going back
  REQUIRE(ev.size() == 2);
  CHECK(ev[0] == Event{10, 345, 8, 0});
  CHECK(ev[1] == Event{400, 1, 8, 1});
  const auto& s = d.stats();
  CHECK(s.x_before_y == 1);
  CHECK(s.y_out_of_range == 2);
  CHECK(s.x_out_of_range == 1);
  CHECK(s.unknown_words == 7);
  CHECK(s.non_monotonic == 1);
  CHECK(s.warnings() == 12);
}

TEST_CASE("davis: orientation bit swaps axes (wire 260 columns x 346 rows)", "[usb]") {
  DavisDecoder d(346, 260, true);
  CHECK(d.width() == 346);
  CHECK(d.height() == 260);
  auto ev = decode(d, {ts(1), row(300), col(100, true), col(260, true)});
  REQUIRE(ev.size() == 1);
  CHECK(ev[0] == Event{1, 300, 100, 1});
  CHECK(d.stats().x_out_of_range == 1);
}

namespace {
// A valid stream with every kind of word, reproducible from `seed`.
std::vector<std::uint16_t> random_stream(unsigned seed, int n) {
  std::mt19937 rng(seed);
  std::vector<std::uint16_t> w = {ts(0), row(0)};
  std::uint16_t t = 0;
  for (int i = 0; i < n; ++i) {
    switch (rng() % 8) {
      case 0: t = static_cast<std::uint16_t>(std::min<int>(0x7FFF, t + rng() % 50)); w.push_back(ts(t)); break;
      case 1: w.push_back(wrap(1)); t = 0; break;
      case 2: w.push_back(row(rng() % 260)); break;
      case 3: w.push_back(code(5, rng() % 256)); break;
      case 4: w.push_back(code(4, rng() % 1024)); break;
      default: w.push_back(col(rng() % 346, rng() % 2)); break;
    }
  }
  return w;
}
}  // namespace

TEST_CASE("davis: a stream cut at every byte decodes exactly as the whole stream", "[usb]") {
  const auto data = bytes(random_stream(7, 301));
  DavisDecoder whole;
  std::vector<Event> ref;
  whole.feed(data, ref);
  REQUIRE(ref.size() > 50);
  for (std::size_t cut = 0; cut <= data.size(); ++cut) {
    DavisDecoder d;
    std::vector<Event> out;
    d.feed(std::span(data).first(cut), out);
    CHECK(d.has_pending_byte() == (cut % 2 == 1));
    d.feed(std::span(data).subspan(cut), out);
    INFO("cut at byte " << cut);
    REQUIRE(out == ref);
    REQUIRE_FALSE(d.has_pending_byte());
  }
  // One byte per USB buffer, and empty buffers in between.
  DavisDecoder d;
  std::vector<Event> out;
  for (std::uint8_t b : data) {
    d.feed(std::span(&b, 1), out);
    d.feed({}, out);
  }
  CHECK(out == ref);
  CHECK(d.stats().words == whole.stats().words);
  CHECK(d.stats().bytes == data.size());
}

TEST_CASE("davis: random garbage never crashes, stays in the sensor and counts warnings", "[usb]") {
  std::mt19937 rng(1234);
  DavisDecoder d;
  std::vector<Event> out;
  std::size_t total = 0;
  for (int chunk = 0; chunk < 400; ++chunk) {
    std::vector<std::uint8_t> buf(rng() % 4099);  // odd sizes and empty buffers included
    for (auto& b : buf) b = static_cast<std::uint8_t>(rng());
    total += buf.size();
    d.feed(buf, out);
  }
  CHECK(d.stats().bytes == total);
  CHECK(d.stats().words == total / 2);
  CHECK(d.has_pending_byte() == (total % 2 == 1));
  CHECK(d.stats().events == out.size());
  CHECK(d.stats().warnings() > 0);
  CHECK(out.size() > 0);
  for (const Event& e : out) {
    REQUIRE(e.x < 346);
    REQUIRE(e.y < 260);
    REQUIRE(e.p <= 1);
    REQUIRE(e.t >= 0);
  }
}
