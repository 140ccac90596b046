// AEDAT 2.0 (DAVIS / DHP19 layout), AEDAT 3.1 and .npy structured arrays, on files built here
// byte by byte (no public sample of these in shared data).
#include <catch2/catch.hpp>

#include "camera/io/aedat_legacy.h"
#include "io_test_util.h"

using yelan::camera::Event;
using namespace yelan::test;

namespace {

void put_be32(std::vector<unsigned char>& b, std::uint32_t v) {
  for (int i = 3; i >= 0; --i) b.push_back(static_cast<unsigned char>(v >> (8 * i)));
}

// DAVIS address: y bits 30..22, x bits 21..12, polarity bit 11, DHP19 camera in bits 3..0.
std::uint32_t davis_addr(unsigned x, unsigned y, unsigned p, unsigned cam) {
  return (y << 22) | (x << 12) | (p << 11) | cam;
}

std::vector<unsigned char> dhp19_like() {
  auto b = raw_header("#!AER-DAT2.0\r\n# This is a raw AE data file created by saveAEData in jAER\r\n"
                      "# HardwareInterface: DAVIS346 (DHP19, 4 cameras)\r\n");
  put_be32(b, davis_addr(345, 259, 1, 0));
  put_be32(b, 1000);
  put_be32(b, davis_addr(10, 20, 0, 3));
  put_be32(b, 1001);
  put_be32(b, 0x80000000u | 5);  // an APS sample: not an event
  put_be32(b, 1002);
  put_be32(b, davis_addr(11, 21, 1, 0) | 0x400u);  // a special event: not a DVS event
  put_be32(b, 1003);
  put_be32(b, davis_addr(1, 2, 0, 0));
  put_be32(b, 0xFFFFFFF0u);  // just before the 32-bit wrap
  put_be32(b, davis_addr(3, 4, 1, 0));
  put_be32(b, 0x10u);  // after it
  return b;
}

}  // namespace

TEST_CASE("AEDAT 2.0 DAVIS layout: big-endian, APS skipped, 32-bit wrap", "[io][aedat2]") {
  ScratchDir dir("aedat2");
  const std::string p = dir.file("dhp19.aedat");
  write_bytes(p, dhp19_like());
  auto r = yelan::camera::open_event_file(p);
  CHECK(r->info().format == "aedat2");
  CHECK(r->info().width == 346);
  CHECK(r->info().height == 260);
  const std::int64_t wrap = std::int64_t{1} << 32;
  CHECK(read_all(*r) == std::vector<Event>{{1000, 345, 259, 1}, {1001, 10, 20, 0}, {0xFFFFFFF0LL, 1, 2, 0},
                                           {wrap + 0x10, 3, 4, 1}});
}

TEST_CASE("AEDAT 2.0 DHP19: one camera picked by address & 0xF", "[io][aedat2][dhp19]") {
  ScratchDir dir("dhp19");
  const std::string p = dir.file("dhp19.aedat");
  write_bytes(p, dhp19_like());
  auto cam3 = yelan::camera::open_aedat_legacy(p, 3);
  CHECK(read_all(*cam3) == std::vector<Event>{{1001, 10, 20, 0}});
  auto cam0 = yelan::camera::open_aedat_legacy(p, 0);
  CHECK(read_all(*cam0).size() == 3);
}

TEST_CASE("AEDAT 3.1 polarity packets: valid bit, overflow, other packets skipped", "[io][aedat3]") {
  ScratchDir dir("aedat3");
  auto b = raw_header("#!AER-DAT3.1\r\n#Format: RAW\r\n#Source 1: DAVIS346\r\n#!END-HEADER\r\n");
  auto packet = [&](std::int16_t type, std::int32_t size, std::int32_t overflow, std::int32_t capacity,
                    std::int32_t number) {
    put_le<std::int16_t>(b, type);
    put_le<std::int16_t>(b, 1);
    put_le<std::int32_t>(b, size);
    put_le<std::int32_t>(b, 4);
    put_le<std::int32_t>(b, overflow);
    put_le<std::int32_t>(b, capacity);
    put_le<std::int32_t>(b, number);
    put_le<std::int32_t>(b, number);
  };
  auto pol = [&](unsigned x, unsigned y, unsigned p, bool valid, std::int32_t ts) {
    put_le<std::uint32_t>(b, (x << 17) | (y << 2) | (p << 1) | (valid ? 1u : 0u));
    put_le<std::int32_t>(b, ts);
  };
  packet(1, 8, 0, 3, 3);
  pol(345, 259, 1, true, 100);
  pol(1, 1, 0, false, 101);  // invalidated
  pol(2, 3, 0, true, 102);
  packet(2, 16, 0, 1, 1);  // a frame-ish packet of another type: skipped
  for (int i = 0; i < 16; ++i) b.push_back(0xEE);
  packet(1, 8, 1, 1, 1);  // after one overflow of the 31-bit counter
  pol(7, 8, 1, true, 5);
  write_bytes(dir.file("a.aedat"), b);
  auto r = yelan::camera::open_event_file(dir.file("a.aedat"));
  CHECK(r->info().format == "aedat3");
  CHECK(r->info().width == 346);
  CHECK(read_all(*r) == std::vector<Event>{{100, 345, 259, 1}, {102, 2, 3, 0}, {(std::int64_t{1} << 31) + 5, 7, 8, 1}});

  b.resize(b.size() - 3);  // cut inside the last packet
  write_bytes(dir.file("cut.aedat"), b);
  auto c = yelan::camera::open_event_file(dir.file("cut.aedat"));
  CHECK_THROWS_WITH(read_all(*c), Catch::Contains("truncated packet: needs 8 bytes, 5 remain"));
}

TEST_CASE("NumPy .npy structured arrays with mixed widths and byte orders", "[io][npy]") {
  ScratchDir dir("npy");
  std::string dict = "{'descr': [('t', '<i8'), ('x', '<i2'), ('y', '>u2'), ('p', '|u1'), ('extra', '<f4')], "
                     "'fortran_order': False, 'shape': (3,), }";
  while ((10 + dict.size() + 1) % 64) dict += ' ';
  dict += '\n';
  std::vector<unsigned char> b = {0x93, 'N', 'U', 'M', 'P', 'Y', 1, 0};
  put_le<std::uint16_t>(b, static_cast<std::uint16_t>(dict.size()));
  b.insert(b.end(), dict.begin(), dict.end());
  auto rec = [&](std::int64_t t, std::int16_t x, std::uint16_t y, std::uint8_t p) {
    put_le<std::int64_t>(b, t);
    put_le<std::int16_t>(b, x);
    b.push_back(static_cast<unsigned char>(y >> 8));
    b.push_back(static_cast<unsigned char>(y));
    b.push_back(p);
    put_le<std::uint32_t>(b, 0);
  };
  rec(11718656, 874, 200, 0);
  rec(11718657, 1279, 719, 1);
  rec(11718658, -3, 5, 1);  // negative x: dropped and counted
  write_bytes(dir.file("e.npy"), b);
  auto r = yelan::camera::open_event_file(dir.file("e.npy"));
  CHECK(r->info().format == "npy");
  CHECK(r->info().events == std::optional<std::uint64_t>(3));
  CHECK(read_all(*r) == std::vector<Event>{{11718656, 874, 200, 0}, {11718657, 1279, 719, 1}});
  CHECK(r->warnings().skipped == 1);

  b.resize(b.size() - 1);
  write_bytes(dir.file("cut.npy"), b);
  CHECK_THROWS_WITH(yelan::camera::open_event_file(dir.file("cut.npy")),
                    Catch::Contains("truncated: the header promises 3 records of 17 bytes"));
}
