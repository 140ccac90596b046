// Prophesee RAW decoders on byte streams built here word by word: EVT 2.1 (no public sample),
// timer wraps of EVT 2.0 and EVT 3.0, vectors, and header variants.
#include <catch2/catch.hpp>

#include "camera/io/event_reader.h"
#include "camera/io/prophesee_raw.h"
#include "io_test_util.h"

using yelan::camera::Event;
using namespace yelan::test;

TEST_CASE("EVT 2.1 vector words expand to one event per set bit", "[io][evt21]") {
  ScratchDir dir("evt21");
  auto b = raw_header("% evt 2.1\n% format EVT21;height=720;width=1280\n% end\n");
  const std::int64_t t0 = 5'000'000 + 17;  // not a multiple of 64
  put_le<std::uint64_t>(b, evt21_time_high(t0));
  put_le<std::uint64_t>(b, evt21_cd(t0, 64, 10, 1, 0x80000001u));      // x 64 and 95, ON
  put_le<std::uint64_t>(b, evt21_cd(t0 + 3, 1248, 719, 0, 0x0000F000u));  // x 1260..1263, OFF
  put_le<std::uint64_t>(b, evt21_time_high(t0 + 64));
  put_le<std::uint64_t>(b, evt21_cd(t0 + 64, 0, 0, 1, 0x4u));           // x 2
  put_le<std::uint64_t>(b, std::uint64_t{0xA} << 60);                    // a trigger: ignored
  write_bytes(dir.file("a.raw"), b);

  auto r = yelan::camera::open_event_file(dir.file("a.raw"));
  CHECK(r->info().format == "evt21");
  CHECK(r->info().width == 1280);
  CHECK(r->info().height == 720);
  const auto ev = read_all(*r);
  const std::vector<Event> want = {{t0, 64, 10, 1},      {t0, 95, 10, 1},      {t0 + 3, 1260, 719, 0},
                                   {t0 + 3, 1261, 719, 0}, {t0 + 3, 1262, 719, 0}, {t0 + 3, 1263, 719, 0},
                                   {t0 + 64, 2, 0, 1}};
  CHECK(ev == want);
  CHECK(r->warnings().total() == 0);
}

TEST_CASE("EVT 2.1 vectors past the sensor edge are dropped and counted", "[io][evt21]") {
  ScratchDir dir("evt21edge");
  auto b = raw_header("% format EVT21;height=10;width=40\n");
  put_le<std::uint64_t>(b, evt21_time_high(0));
  put_le<std::uint64_t>(b, evt21_cd(1, 32, 3, 1, 0xFF00u | 0x1u));  // x 32 ok, 40..47 outside
  write_bytes(dir.file("e.raw"), b);
  auto r = yelan::camera::open_event_file(dir.file("e.raw"));
  const auto ev = read_all(*r);
  REQUIRE(ev.size() == 1);
  CHECK(ev[0] == Event{1, 32, 3, 1});
  CHECK(r->warnings().out_of_range == 8);
  CHECK(r->warnings().first.find("outside the 40x10 sensor") != std::string::npos);
}

TEST_CASE("EVT 2.0 timer wrap after 2^34 us continues forward", "[io][evt2]") {
  ScratchDir dir("evt2wrap");
  auto b = raw_header("% evt 2.0\n% geometry 640x480\n");
  const std::int64_t period = std::int64_t{1} << 34;
  const std::int64_t before = period - 64;  // last time-high slot before the wrap
  put_le<std::uint32_t>(b, evt2_time_high(before));
  put_le<std::uint32_t>(b, evt2_cd(before + 5, 1, 2, 1));
  put_le<std::uint32_t>(b, evt2_time_high(0));  // the 34-bit counter wrapped
  put_le<std::uint32_t>(b, evt2_cd(7, 3, 4, 0));
  write_bytes(dir.file("w.raw"), b);
  const auto ev = read_all(dir.file("w.raw"));
  REQUIRE(ev.size() == 2);
  CHECK(ev[0] == Event{before + 5, 1, 2, 1});
  CHECK(ev[1] == Event{period + 7, 3, 4, 0});
}

TEST_CASE("EVT 3.0 24-bit timer wrap, vectors and polarity", "[io][evt3]") {
  ScratchDir dir("evt3wrap");
  auto b = raw_header("% evt 3.0\n% geometry 1280x720\n");
  auto w = [&](unsigned type, unsigned v) { put_le<std::uint16_t>(b, evt3(type, v)); };
  w(0x8, 0xFFF);                 // TIME_HIGH: 4095 << 12
  w(0x6, 0xFFE);                 // TIME_LOW
  w(0x0, 100);                   // ADDR_Y 100
  w(0x2, (1u << 11) | 640);      // ADDR_X: x 640, ON
  w(0x3, (0u << 11) | 1000);     // VECT_BASE_X 1000, OFF
  w(0x4, 0x801);                 // VECT_12: x 1000 and 1011
  w(0x5, 0x03);                  // VECT_8: from x 1012: 1012, 1013
  w(0x8, 0x000);                 // TIME_HIGH wraps to 0
  w(0x6, 0x005);
  w(0x2, 7);                     // x 7, OFF
  write_bytes(dir.file("v.raw"), b);
  const std::int64_t t1 = (std::int64_t{4095} << 12) | 0xFFE, t2 = (std::int64_t{1} << 24) + 5;
  const auto ev = read_all(dir.file("v.raw"));
  const std::vector<Event> want = {{t1, 640, 100, 1}, {t1, 1000, 100, 0}, {t1, 1011, 100, 0},
                                   {t1, 1012, 100, 0}, {t1, 1013, 100, 0}, {t2, 7, 100, 0}};
  CHECK(ev == want);
}

TEST_CASE("EVT 3.0 small step back of TIME_HIGH is reported, not taken for a wrap", "[io][evt3]") {
  ScratchDir dir("evt3back");
  auto b = raw_header("% evt 3.0\n% geometry 1280x720\n");
  auto w = [&](unsigned type, unsigned v) { put_le<std::uint16_t>(b, evt3(type, v)); };
  w(0x8, 10);
  w(0x0, 1);
  w(0x2, 5);
  w(0x8, 9);  // back by one TIME_HIGH step
  w(0x2, 6);
  write_bytes(dir.file("b.raw"), b);
  auto r = yelan::camera::open_event_file(dir.file("b.raw"));
  const auto ev = read_all(*r);
  REQUIRE(ev.size() == 2);
  CHECK(ev[0].t == 10 << 12);
  CHECK(ev[1].t == 9 << 12);  // kept as read
  CHECK(r->warnings().backwards == 1);
  CHECK(r->warnings().first.find("backwards") != std::string::npos);
}

TEST_CASE("RAW header: geometry, format line, plugin name and % end", "[io][raw]") {
  ScratchDir dir("hdr");
  const std::string p = dir.file("h.raw");
  write_text(p, "% plugin_name hal_plugin_gen3_fx3\n% evt 2.0\n");
  auto h = yelan::camera::parse_raw_header(p);
  CHECK(h.evt == "2.0");
  CHECK(h.width == 640);
  CHECK(h.height == 480);
  write_text(p, "% format EVT3;height=320;width=320\n% end\n%\x01\x02");
  h = yelan::camera::parse_raw_header(p);
  CHECK(h.evt == "3.0");
  CHECK(h.width == 320);
  CHECK(h.data_offset == 41);  // the bytes after `% end` are data even if they start with '%'
  write_text(p, "% evt 4.0\n");
  CHECK_THROWS_WITH(yelan::camera::open_event_file(p), Catch::Contains("unsupported Prophesee event format '4.0'"));
}
