// Writers: read -> write -> read is lossless for ours (HDF5), AEDAT 4.0 and text; outputs are
// atomic (no temporary left, an unfinished writer leaves nothing) and ours is byte-reproducible.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cstring>
#include <random>

#include <zstd.h>

#include "camera/io/compression.h"
#include "camera/io/event_writer.h"
#include "camera/io/flatbuf.h"
#include "camera/io/h5.h"
#include "io_test_util.h"
#include "test_util.h"

using yelan::camera::Event;
using yelan::camera::StreamInfo;
using namespace yelan::test;

namespace {

// A stream with repeated timestamps, both polarities, corners of the sensor and an odd count.
std::vector<Event> synthetic_stream(std::size_t n, int w, int h, std::int64_t t0, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<Event> ev;
  std::int64_t t = t0;
  for (std::size_t i = 0; i < n; ++i) {
    t += static_cast<std::int64_t>(rng() % 3);  // 0, 1 or 2 us steps
    ev.push_back({t, static_cast<std::uint16_t>(rng() % static_cast<unsigned>(w)),
                  static_cast<std::uint16_t>(rng() % static_cast<unsigned>(h)), static_cast<std::uint8_t>(rng() & 1)});
  }
  ev.push_back({t + 1, static_cast<std::uint16_t>(w - 1), static_cast<std::uint16_t>(h - 1), 1});
  ev.push_back({t + 1, 0, 0, 0});
  return ev;
}

void write_all(const std::string& path, const StreamInfo& info, const std::vector<Event>& ev, std::size_t batch) {
  auto w = yelan::camera::open_event_writer(path, info);
  for (std::size_t i = 0; i < ev.size(); i += batch)
    w->write(std::span<const Event>(ev).subspan(i, std::min(batch, ev.size() - i)));
  w->close();
}

// A temporary file of `path` (path.tmp-PID-XXXXXX) exists beside it.
bool temp_beside(const std::string& path) {
  const std::filesystem::path p(path);
  for (const auto& e : std::filesystem::directory_iterator(p.parent_path()))
    if (e.path().filename().string().rfind(p.filename().string() + ".tmp-", 0) == 0) return true;
  return false;
}

void check_roundtrip(const std::string& ext, const std::string& format, bool keeps_size) {
  ScratchDir dir("rt" + format);
  const auto ev = synthetic_stream(100'003, 346, 260, 1'633'953'690'975'950, 7);
  const std::string path = dir.file("out" + ext);
  write_all(path, {"", 346, 260, {}, {}}, ev, 9'999);
  CHECK_FALSE(temp_beside(path));
  auto r = yelan::camera::open_event_file(path);
  CHECK(r->info().format == format);
  if (keeps_size) {
    CHECK(r->info().width == 346);
    CHECK(r->info().height == 260);
  }
  const auto back = read_all(*r);
  REQUIRE(back.size() == ev.size());
  CHECK(back == ev);
  CHECK(r->warnings().total() == 0);
  // Seeking lands on the first event at or after T, by index or by decoding.
  const Event& mid = ev[ev.size() / 2 + 1];
  r->seek(mid.t);
  const auto from = std::find_if(ev.begin(), ev.end(), [&](const Event& e) { return e.t >= mid.t; });
  CHECK(read_all(*r) == std::vector<Event>(from, ev.end()));
}

void roundtrip_real(const std::string& rel, const std::string& ext) {
  const std::string src = shared_data_or_skip(rel);
  ScratchDir dir("rtreal");
  auto in = yelan::camera::open_event_file(src);
  const auto ev = read_all(*in);
  const std::string path = dir.file("copy" + ext);
  write_all(path, in->info(), ev, 65536);
  auto r = yelan::camera::open_event_file(path);
  CHECK(r->info().width == in->info().width);
  CHECK(r->info().height == in->info().height);
  CHECK(read_all(*r) == ev);
}

}  // namespace

TEST_CASE("ours (HDF5) round trip is lossless", "[io][h5][roundtrip]") { check_roundtrip(".yelan.h5", "yelan-h5", true); }
TEST_CASE("AEDAT 4.0 round trip is lossless", "[io][aedat4][roundtrip]") { check_roundtrip(".aedat4", "aedat4", true); }
TEST_CASE("text round trip is lossless", "[io][text][roundtrip]") { check_roundtrip(".txt", "text", true); }

TEST_CASE("real files survive read -> write ours/text/aedat4 -> read", "[io][roundtrip][real]") {
  roundtrip_real("events/evt3_sample.raw", ".yelan.h5");
  roundtrip_real("events/evt2_sample.raw", ".txt");
  roundtrip_real("events/aestream_davis.aedat4", ".aedat4");
  roundtrip_real("events/aestream_davis.aedat4", ".h5");
}

TEST_CASE("ours: layout, attributes and millisecond index", "[io][h5]") {
  namespace h5 = yelan::camera::h5;
  ScratchDir dir("h5layout");
  // t: 999, 1000, 1000, 2500, 4000 -> t0 = 0 ms; boundaries 0,1000,2000,3000,4000,5000.
  const std::vector<Event> ev = {{999, 1, 2, 1}, {1000, 3, 4, 0}, {1000, 5, 6, 1}, {2500, 7, 8, 0}, {4000, 9, 9, 1}};
  const std::string path = dir.file("x.yelan.h5");
  write_all(path, {"", 10, 10, {}, {}}, ev, 2);
  h5::H5Id f = h5::open_file(path);
  CHECK(h5::read_attr_string(f.get(), "format") == std::optional<std::string>("yelan-recording"));
  CHECK(h5::read_attr_i64(f.get(), "version") == std::optional<std::int64_t>(1));
  CHECK(h5::read_attr_i64(f.get(), "width") == std::optional<std::int64_t>(10));
  CHECK(h5::read_attr_i64(f.get(), "height") == std::optional<std::int64_t>(10));
  h5::H5Id ms = h5::check(H5Dopen2(f.get(), "events/ms_to_idx", H5P_DEFAULT), "ms_to_idx");
  REQUIRE(h5::shape(ms.get()) == std::vector<hsize_t>{6});
  std::vector<std::uint64_t> idx(6);
  h5::read_rows(ms.get(), H5T_NATIVE_UINT64, 0, 6, idx.data());
  CHECK(idx == std::vector<std::uint64_t>{0, 1, 3, 4, 4, 5});
  CHECK(h5::read_attr_i64(ms.get(), "t0_us") == std::optional<std::int64_t>(0));
  for (const char* name : {"events/t", "events/x", "events/y", "events/p"}) {
    h5::H5Id ds = h5::check(H5Dopen2(f.get(), name, H5P_DEFAULT), name);
    h5::H5Id dcpl = h5::check(H5Dget_create_plist(ds.get()), "dcpl");
    CHECK(H5Pget_layout(dcpl.get()) == H5D_CHUNKED);
    CHECK(H5Pget_nfilters(dcpl.get()) >= 1);  // shuffle + deflate
  }

  auto r = yelan::camera::open_event_file(path);
  CHECK(r->fast_seek());
  CHECK(r->info().events == std::optional<std::uint64_t>(5));
  CHECK(r->info().t_first == std::optional<std::int64_t>(999));
  r->seek(2000);
  auto rest = read_all(*r);
  CHECK(rest == std::vector<Event>(ev.begin() + 3, ev.end()));
  r->seek(4001);
  CHECK(read_all(*r).empty());
}

TEST_CASE("ours is byte-reproducible: the same events give the same bytes", "[io][h5]") {
  ScratchDir dir("h5repro");
  const auto ev = synthetic_stream(5'001, 64, 48, 0, 3);
  write_all(dir.file("a.yelan.h5"), {"", 64, 48, {}, {}}, ev, 1000);
  write_all(dir.file("b.yelan.h5"), {"", 64, 48, {}, {}}, ev, 777);
  CHECK(read_bytes(dir.file("a.yelan.h5")) == read_bytes(dir.file("b.yelan.h5")));
}

TEST_CASE("text writer: header line, integer microseconds, no rebasing", "[io][text]") {
  ScratchDir dir("textw");
  const std::string path = dir.file("e.txt");
  write_all(path, {"", 0, 0, {}, {}}, {{1633953690975950, 218, 15, 1}, {1633953690975954, 178, 73, 0}}, 10);
  const auto b = read_bytes(path);
  CHECK(std::string(b.begin(), b.end()) == "# t_us x y p\n1633953690975950 218 15 1\n1633953690975954 178 73 0\n");
}

TEST_CASE("text reader: seconds (RPG/ESIM), commas, -1 polarity, size line", "[io][text]") {
  ScratchDir dir("textr");
  const std::string path = dir.file("rpg.txt");
  write_text(path, "240 180\n0.000001 1 2 1\n1.5,3,4,-1\n\n12.3456785 5 6 0\n1e-3 7 8 1\n");
  auto r = yelan::camera::open_event_file(path);
  CHECK(r->info().width == 240);
  CHECK(r->info().height == 180);
  const auto ev = read_all(*r);
  const std::vector<Event> want = {{1, 1, 2, 1}, {1500000, 3, 4, 0}, {12345679, 5, 6, 0}, {1000, 7, 8, 1}};
  CHECK(ev == want);
  CHECK(r->warnings().backwards == 1);  // 1e-3 s after 12.3 s
}

TEST_CASE("a writer destroyed before close leaves no file behind", "[io][atomic]") {
  ScratchDir dir("atomic");
  for (const char* name : {"a.yelan.h5", "a.aedat4", "a.txt"}) {
    const std::string path = dir.file(name);
    {
      auto w = yelan::camera::open_event_writer(path, {"", 4, 4, {}, {}});
      const std::vector<Event> ev = {{1, 1, 1, 1}};
      w->write(ev);
      CHECK(temp_beside(path));
    }
    CHECK_FALSE(std::filesystem::exists(path));
    CHECK_FALSE(temp_beside(path));
  }
}

TEST_CASE("AEDAT 4.0 writer emits a data table the header points to", "[io][aedat4]") {
  ScratchDir dir("a4table");
  const auto ev = synthetic_stream(20'000, 32, 32, 100, 11);
  const std::string path = dir.file("t.aedat4");
  write_all(path, {"", 32, 32, {}, {}}, ev, 4096);
  const auto b = read_bytes(path);
  REQUIRE(b.size() > 60);
  CHECK(std::string(b.begin(), b.begin() + 14) == "#!AER-DAT4.0\r\n");
  CHECK(std::string(b.begin() + 22, b.begin() + 26) == "IOHE");
  std::int64_t table = 0;
  std::memcpy(&table, b.data() + 14 + 32, 8);
  REQUIRE(table > 0);
  REQUIRE(static_cast<std::size_t>(table) < b.size());
  // The table is an LZ4 frame (magic 0x184D2204) reaching to the end of the file.
  CHECK(b[static_cast<std::size_t>(table)] == 0x04);
  CHECK(b[static_cast<std::size_t>(table) + 1] == 0x22);
  CHECK(b[static_cast<std::size_t>(table) + 2] == 0x4D);
  CHECK(b[static_cast<std::size_t>(table) + 3] == 0x18);

  // Decoded, it is a size-prefixed FTAB flatbuffer with one entry per packet of 8192 events.
  std::vector<unsigned char> plain;
  std::string problem;
  REQUIRE(yelan::camera::decompress(yelan::camera::Codec::lz4, b.data() + table, b.size() - static_cast<std::size_t>(table),
                                    1 << 20, plain, problem));
  REQUIRE(plain.size() > 12);
  CHECK(std::string(plain.begin() + 8, plain.begin() + 12) == "FTAB");
  namespace flat = yelan::camera::flat;
  flat::Table root = flat::root(plain.data() + 4, plain.size() - 4);
  auto defs = flat::field_vector(root, 0, 4);
  REQUIRE(defs);
  REQUIRE(defs->second == 3);  // 20002 events: 8192 + 8192 + 3618
  const std::int64_t want_count[3] = {8192, 8192, 3618};
  const std::size_t want_first[3] = {0, 8192, 16384};
  for (std::size_t i = 0; i < 3; ++i) {
    flat::Table d = flat::table_at(plain.data() + 4, plain.size() - 4, defs->first + 4 * i);
    const std::int64_t at = flat::field_i64(d, 0, -1);
    std::int32_t stream = -1, size = 0;
    std::memcpy(&stream, b.data() + at - 8, 4);
    std::memcpy(&size, b.data() + at - 4, 4);
    CHECK(stream == 0);
    auto info = flat::field(d, 1, 8);
    REQUIRE(info);
    std::int32_t table_stream = -1, table_size = 0;
    std::memcpy(&table_stream, plain.data() + 4 + *info, 4);
    std::memcpy(&table_size, plain.data() + 4 + *info + 4, 4);
    CHECK(table_stream == 0);
    CHECK(table_size == size);
    CHECK(flat::field_i64(d, 2, -1) == want_count[i]);
    CHECK(flat::field_i64(d, 3, -1) == ev[want_first[i]].t);
    CHECK(flat::field_i64(d, 4, -1) == ev[want_first[i] + static_cast<std::size_t>(want_count[i]) - 1].t);
  }
}

TEST_CASE("AEDAT 4.0 with Zstd packets reads the same events", "[io][aedat4][zstd]") {
  // DV can write Zstd (compression 3/4); rebuild one of our LZ4 files packet by packet.
  ScratchDir dir("zstd");
  const auto ev = synthetic_stream(10'000, 64, 48, 5'000, 21);
  const std::string lz4_path = dir.file("l.aedat4"), zstd_path = dir.file("z.aedat4");
  write_all(lz4_path, {"", 64, 48, {}, {}}, ev, 3000);
  const auto b = read_bytes(lz4_path);
  std::uint32_t hdr = 0;
  std::int64_t table = 0;
  std::memcpy(&hdr, b.data() + 14, 4);
  std::memcpy(&table, b.data() + 46, 8);
  std::vector<unsigned char> out(b.begin(), b.begin() + 18 + hdr);
  const std::int32_t zstd = 3;
  const std::int64_t none = -1;
  std::memcpy(out.data() + 42, &zstd, 4);  // IOHeader.compression
  std::memcpy(out.data() + 46, &none, 8);  // no data table
  int packets = 0;
  std::size_t last_packet = 0;
  for (std::size_t at = 18 + hdr; at < static_cast<std::size_t>(table); ++packets) {
    std::int32_t stream = 0, size = 0;
    std::memcpy(&stream, b.data() + at, 4);
    std::memcpy(&size, b.data() + at + 4, 4);
    std::vector<unsigned char> plain;
    std::string problem;
    REQUIRE(yelan::camera::decompress(yelan::camera::Codec::lz4, b.data() + at + 8, static_cast<std::size_t>(size),
                                      1 << 24, plain, problem));
    std::vector<unsigned char> z(ZSTD_compressBound(plain.size()));
    const std::size_t zn = ZSTD_compress(z.data(), z.size(), plain.data(), plain.size(), 3);
    REQUIRE_FALSE(ZSTD_isError(zn));
    const std::int32_t zsize = static_cast<std::int32_t>(zn);
    last_packet = out.size();
    out.insert(out.end(), b.begin() + static_cast<std::ptrdiff_t>(at), b.begin() + static_cast<std::ptrdiff_t>(at + 4));
    out.insert(out.end(), reinterpret_cast<const unsigned char*>(&zsize), reinterpret_cast<const unsigned char*>(&zsize) + 4);
    out.insert(out.end(), z.begin(), z.begin() + static_cast<std::ptrdiff_t>(zn));
    at += 8 + static_cast<std::size_t>(size);
  }
  CHECK(packets == 2);  // 10002 events, 8192 per packet
  write_bytes(zstd_path, out);
  auto r = yelan::camera::open_event_file(zstd_path);
  CHECK_FALSE(r->fast_seek());
  CHECK(read_all(*r) == ev);

  // A Zstd frame cut short (the packet and file one byte shorter) is an error at its payload.
  std::int32_t last_size = 0;
  std::memcpy(&last_size, out.data() + last_packet + 4, 4);
  --last_size;
  std::memcpy(out.data() + last_packet + 4, &last_size, 4);
  out.pop_back();
  write_bytes(zstd_path, out);
  r = yelan::camera::open_event_file(zstd_path);
  CHECK_THROWS_WITH(read_all(*r), zstd_path + ": offset " + std::to_string(last_packet + 8) +
                                      ": Zstd packet ends before its frame does");
}
