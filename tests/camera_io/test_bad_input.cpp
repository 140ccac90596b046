// Bad input never crashes or hangs: truncated files at many cut points, wrong magic, corrupt
// compressed packets, absurd sizes, out-of-range coordinates and timestamps going backwards
// give a FormatError naming file, offset and problem, or a counted warning.
#include <catch2/catch.hpp>

#include <cstring>
#include <limits>

#include "camera/io/event_writer.h"
#include "io_test_util.h"
#include "test_util.h"

using yelan::camera::Event;
using yelan::camera::FormatError;
using namespace yelan::test;

namespace {

enum class Outcome { error, fewer, all };

struct Result {
  Outcome outcome;
  std::size_t events = 0;
  std::uint64_t warnings = 0;
  std::string message;
};

Result try_read(const std::string& path, std::size_t full_count) {
  try {
    auto r = yelan::camera::open_event_file(path);
    auto ev = read_all(*r);
    return {ev.size() == full_count ? Outcome::all : Outcome::fewer, ev.size(), r->warnings().total(), ""};
  } catch (const FormatError& e) {
    return {Outcome::error, 0, 0, e.what()};
  }
}

std::vector<unsigned char> prefix(const std::vector<unsigned char>& b, std::size_t n) {
  return std::vector<unsigned char>(b.begin(), b.begin() + static_cast<std::ptrdiff_t>(n));
}

// Cut points: every byte of the first 300, then 97 spread over the rest.
std::vector<std::size_t> cut_points(std::size_t size) {
  std::vector<std::size_t> cuts;
  for (std::size_t i = 0; i < std::min<std::size_t>(300, size); ++i) cuts.push_back(i);
  for (std::size_t k = 1; k < 98; ++k) cuts.push_back(300 + (size - 300) * k / 98 + (k % 7));
  return cuts;
}

}  // namespace

TEST_CASE("truncated AEDAT 4.0 always gives a FormatError with the file and an offset", "[io][aedat4][bad]") {
  const auto b = read_bytes(shared_data_or_skip("events/aestream_davis.aedat4"));
  ScratchDir dir("trunc4");
  const std::string p = dir.file("t.aedat4");
  for (std::size_t cut : cut_points(b.size())) {
    write_bytes(p, prefix(b, cut));
    Result r = try_read(p, 117667);
    INFO("cut at " << cut);
    REQUIRE(r.outcome == Outcome::error);
    CHECK(r.message.rfind(p + ": offset ", 0) == 0);
  }
  // Cut exactly between two packets: the missing data table gives it away.
  write_bytes(p, prefix(b, 1190063));
  CHECK(try_read(p, 117667).outcome == Outcome::all);  // up to the table: every event is there
  write_bytes(p, prefix(b, 1190063 - 1));
  CHECK_THAT(try_read(p, 117667).message, Catch::Contains("truncated packet"));
}

TEST_CASE("truncated RAW files: fewer events, a counted partial word, or a header error", "[io][raw][bad]") {
  for (const char* rel : {"events/evt3_sample.raw", "events/evt2_sample.raw"}) {
    const auto b = read_bytes(shared_data_or_skip(rel));
    auto full = yelan::camera::open_event_file(shared_data_or_skip(rel));
    const std::size_t full_count = read_all(*full).size();
    ScratchDir dir("truncraw");
    const std::string p = dir.file("t.raw");
    for (std::size_t cut : cut_points(b.size())) {
      write_bytes(p, prefix(b, cut));
      INFO(rel << " cut at " << cut);
      Result r = try_read(p, full_count);
      if (r.outcome == Outcome::error) {
        CHECK(r.message.rfind(p + ": offset ", 0) == 0);
      } else {
        CHECK(r.events <= full_count);
      }
    }
  }
}

TEST_CASE("a RAW file cut inside a word counts the leftover bytes", "[io][raw][bad]") {
  ScratchDir dir("partial");
  auto b = raw_header("% evt 2.0\n% geometry 640x480\n");
  put_le<std::uint32_t>(b, evt2_time_high(64));
  put_le<std::uint32_t>(b, evt2_cd(65, 1, 1, 1));
  b.push_back(0x12);
  b.push_back(0x34);
  write_bytes(dir.file("p.raw"), b);
  auto r = yelan::camera::open_event_file(dir.file("p.raw"));
  CHECK(read_all(*r).size() == 1);
  CHECK(r->warnings().skipped == 1);
  CHECK_THAT(r->warnings().first, Catch::Contains("file ends inside a 4-byte word"));
}

TEST_CASE("wrong magic and unknown files are refused with offset 0", "[io][bad]") {
  ScratchDir dir("magic");
  const std::string a = dir.file("x.aedat4");
  write_text(a, "#!AER-DAT4.1\r\nrest");
  CHECK_THROWS_WITH(yelan::camera::open_event_file(a), a + ": offset 0: not an AEDAT 4.0 file (bad magic)");
  const std::string b = dir.file("x.bin");
  write_bytes(b, {0x00, 0xFF, 0x13, 0x37});
  CHECK_THROWS_WITH(yelan::camera::open_event_file(b), Catch::Contains("unknown event file format"));
  const std::string h = dir.file("x.h5");
  write_text(h, "\x89HDF\r\n\x1a\nnot really");
  CHECK_THROWS_WITH(yelan::camera::open_event_file(h), h + ": offset 0: not a readable HDF5 file");
  CHECK_THROWS_AS(yelan::camera::open_event_file(dir.file("missing.raw")), FormatError);
}

TEST_CASE("AEDAT 4.0 corrupt packets and absurd sizes", "[io][aedat4][bad]") {
  const auto orig = read_bytes(shared_data_or_skip("events/aestream_davis.aedat4"));
  ScratchDir dir("corrupt4");
  const std::string p = dir.file("c.aedat4");
  // The first packet header follows the IOHeader: 14 + 4 + size.
  std::uint32_t hdr = 0;
  std::memcpy(&hdr, orig.data() + 14, 4);
  const std::size_t first = 18 + hdr;

  auto b = orig;  // absurd packet size
  const std::int32_t huge = 0x7FFFFFF0;
  std::memcpy(b.data() + first + 4, &huge, 4);
  write_bytes(p, b);
  std::vector<Event> sink;
  CHECK_THROWS_WITH(yelan::camera::open_event_file(p)->read(sink, 1), Catch::Contains("absurd packet size"));

  b = orig;  // negative size
  const std::int32_t neg = -5;
  std::memcpy(b.data() + first + 4, &neg, 4);
  write_bytes(p, b);
  auto r = yelan::camera::open_event_file(p);
  CHECK_THROWS_WITH(read_all(*r), p + ": offset " + std::to_string(first + 4) + ": absurd packet size -5");

  b = orig;  // undeclared stream id
  const std::int32_t stream = 9;
  std::memcpy(b.data() + first, &stream, 4);
  write_bytes(p, b);
  r = yelan::camera::open_event_file(p);
  CHECK_THROWS_WITH(read_all(*r), Catch::Contains("stream 9, which the header does not declare"));

  // The first event packet (stream 0): packets of other streams are skipped unread.
  std::size_t ev0 = first;
  for (std::int32_t id = -1, len = 0;; ev0 += 8 + static_cast<std::size_t>(len)) {
    std::memcpy(&id, orig.data() + ev0, 4);
    std::memcpy(&len, orig.data() + ev0 + 4, 4);
    if (id == 0) break;
  }
  b = orig;  // corrupt LZ4 frame: its magic number
  b[ev0 + 8] ^= 0xFF;
  write_bytes(p, b);
  r = yelan::camera::open_event_file(p);
  CHECK_THROWS_WITH(read_all(*r), p + ": offset " + std::to_string(ev0 + 8) +
                                      ": corrupt LZ4 packet: ERROR_frameType_unknown");

  b = orig;  // the packet claims 100 bytes fewer than its LZ4 frame needs
  std::int32_t size = 0;
  std::memcpy(&size, b.data() + ev0 + 4, 4);
  size -= 100;
  std::memcpy(b.data() + ev0 + 4, &size, 4);
  write_bytes(p, b);
  r = yelan::camera::open_event_file(p);
  CHECK_THROWS_WITH(read_all(*r), Catch::Contains("LZ4 packet ends before its frame does"));

  b = orig;  // garbage inside the compressed bytes: an error or changed events, never a crash
  for (std::size_t i = ev0 + 8 + 20; i < ev0 + 8 + 60; ++i) b[i] ^= 0xA5;
  write_bytes(p, b);
  Result garbled = try_read(p, 117667);
  CHECK((garbled.outcome == Outcome::error || garbled.warnings > 0 || garbled.events <= 117667));

  b = orig;  // absurd header size
  const std::uint32_t big = 0xFFFFFFF0u;
  std::memcpy(b.data() + 14, &big, 4);
  write_bytes(p, b);
  CHECK_THROWS_WITH(yelan::camera::open_event_file(p), p + ": offset 14: absurd header size 4294967280");
}

TEST_CASE("AEDAT 4.0 header whose info string runs past its flatbuffer", "[io][aedat4][bad]") {
  // The bounds checks of the hand-written flatbuffer reader: a string length of 16 M in a
  // header of a few hundred bytes.
  ScratchDir dir("flat4");
  const std::string p = dir.file("f.aedat4");
  {
    auto w = yelan::camera::open_event_writer(p, {"", 8, 8, {}, {}});
    const std::vector<Event> ev = {{1, 1, 1, 1}, {2, 2, 2, 0}};
    w->write(ev);
    w->close();
  }
  auto b = read_bytes(p);
  const std::uint32_t bad_len = 0x00FFFFFF;
  std::memcpy(b.data() + 18 + 40, &bad_len, 4);  // the infoNode string length
  write_bytes(p, b);
  CHECK_THROWS_WITH(yelan::camera::open_event_file(p), Catch::Contains("offset 18: malformed IOHeader"));
}

TEST_CASE("out-of-range coordinates: an error in text, dropped and counted in AEDAT", "[io][bad]") {
  ScratchDir dir("range");
  const std::string t = dir.file("r.txt");
  write_text(t, "# t_us x y p\n1 2 3 1\n2 70000 3 1\n");
  auto r = yelan::camera::open_event_file(t);
  CHECK_THROWS_WITH(read_all(*r), t + ": offset 21: line 3: bad coordinates '70000 3'");
  write_text(t, "# t_us x y p\n1 2 3 7\n");
  r = yelan::camera::open_event_file(t);
  CHECK_THROWS_WITH(read_all(*r), Catch::Contains("bad polarity '7'"));
  write_text(t, "# t_us x y p\n1 2 3\n");
  r = yelan::camera::open_event_file(t);
  CHECK_THROWS_WITH(read_all(*r), Catch::Contains("expected 4 fields `t x y p`, got 3"));

  const std::string a = dir.file("r.aedat4");
  {
    auto w = yelan::camera::open_event_writer(a, {"", 346, 260, {}, {}});  // declares 346x260
    const std::vector<Event> ev = {{1, 345, 259, 1}, {2, 346, 10, 0}, {3, 10, 260, 1}, {4, 0, 0, 0}};
    w->write(ev);
    w->close();
  }
  auto ra = yelan::camera::open_event_file(a);
  const auto ev = read_all(*ra);
  CHECK(ev == std::vector<Event>{{1, 345, 259, 1}, {4, 0, 0, 0}});
  CHECK(ra->warnings().out_of_range == 2);
}

TEST_CASE("timestamps going backwards are kept, counted and reported", "[io][bad]") {
  ScratchDir dir("back");
  const std::string t = dir.file("b.txt");
  write_text(t, "# t_us x y p\n10 0 0 1\n5 0 0 1\n20 0 0 1\n19 0 0 0\n");
  auto r = yelan::camera::open_event_file(t);
  const auto ev = read_all(*r);
  REQUIRE(ev.size() == 4);
  CHECK(ev[1].t == 5);
  CHECK(r->warnings().backwards == 2);
  CHECK_THAT(r->warnings().first, Catch::Contains("timestamp goes backwards from 10 to 5 us"));
}

TEST_CASE("truncated and corrupted ours (HDF5) gives FormatErrors", "[io][h5][bad]") {
  ScratchDir dir("h5bad");
  const std::string good = dir.file("g.yelan.h5");
  {
    auto w = yelan::camera::open_event_writer(good, {"", 64, 64, {}, {}});
    std::vector<Event> ev;
    for (int i = 0; i < 200'000; ++i) ev.push_back({i, static_cast<std::uint16_t>(i % 64), static_cast<std::uint16_t>((i / 64) % 64), static_cast<std::uint8_t>(i & 1)});
    w->write(ev);
    w->close();
  }
  const auto b = read_bytes(good);
  const std::string p = dir.file("t.yelan.h5");
  for (std::size_t k = 1; k < 40; ++k) {
    const std::size_t cut = b.size() * k / 40;
    write_bytes(p, prefix(b, cut));
    INFO("cut at " << cut << " of " << b.size());
    Result r = try_read(p, 200'000);
    CHECK(r.outcome != Outcome::all);
    if (r.outcome == Outcome::error) CHECK(r.message.rfind(p + ": offset ", 0) == 0);
  }
  // Flip bytes in the middle (inside compressed chunks).
  auto c = b;
  for (std::size_t i = c.size() / 2; i < c.size() / 2 + 64; ++i) c[i] ^= 0xFF;
  write_bytes(p, c);
  Result r = try_read(p, 200'000);
  CHECK(r.outcome != Outcome::all);
}

TEST_CASE("fuzz finding: an HDF5 chunk claiming 4 GB is refused before HDF5 allocates it", "[io][h5][bad][fuzz]") {
  // Found by tests/fuzz/fuzz_hdf5: a mutated copy of one of our files whose chunk index says
  // the first chunk of /events/t holds 4,294,964,836 bytes at byte 14,303 of a 15,475-byte file.
  const std::string p = (std::filesystem::path(__FILE__).parent_path() / "data" / "fuzz_hdf5_huge_chunk.h5").string();
  REQUIRE(std::filesystem::exists(p));
  CHECK_THROWS_WITH(yelan::camera::open_event_file(p),
                    p + ": offset 0: HDF5: chunk at row 0 claims 4294964836 bytes at address 14303 of a 15475-byte file");
}

TEST_CASE("fuzz finding: a chunk stored smaller than its shape behind a shuffle-only pipeline is refused", "[io][h5][bad][fuzz]") {
  // Found by tests/fuzz/fuzz_recording: a mutated recording whose /events/ms_to_idx lost its
  // deflate filter, leaving shuffle alone over a 149-byte chunk of a 4096 x 8-byte shape;
  // libhdf5 then copied 32768 bytes out of the 149 (a heap overflow under ASan).
  namespace h5 = yelan::camera::h5;
  const std::string p = (std::filesystem::path(__FILE__).parent_path() / "data" / "fuzz_recording_short_chunk.h5").string();
  REQUIRE(std::filesystem::exists(p));
  h5::H5Id f = h5::open_file(p);
  h5::H5Id ds = h5::check(H5Dopen2(f.get(), "events/ms_to_idx", H5P_DEFAULT), "open ms_to_idx");
  CHECK_THROWS_WITH(h5::check_stored_chunks(ds.get(), 0, 1, std::filesystem::file_size(p), 1u << 30),
                    "chunk at row 0 stores 149 bytes where its shape needs 32768 and its filters cannot expand it");
  // The same file's compressed columns keep passing: deflate may expand what it stores.
  h5::H5Id t = h5::check(H5Dopen2(f.get(), "events/t", H5P_DEFAULT), "open t");
  CHECK_NOTHROW(h5::check_stored_chunks(t.get(), 0, 1, std::filesystem::file_size(p), 1u << 30));
}

TEST_CASE("fuzz finding: a .npy dtype field without its closing parenthesis", "[io][npy][bad][fuzz]") {
  // Found by tests/fuzz/fuzz_npy: the field scan restarted from the top of the header forever.
  ScratchDir dir("npyparen");
  const std::string dict = "{'descr': [('t', '<i8'] }\n";
  std::vector<unsigned char> b = {0x93, 'N', 'U', 'M', 'P', 'Y', 1, 0, static_cast<unsigned char>(dict.size()), 0};
  b.insert(b.end(), dict.begin(), dict.end());
  write_bytes(dir.file("p.npy"), b);
  CHECK_THROWS_WITH(yelan::camera::open_event_file(dir.file("p.npy")),
                    dir.file("p.npy") + ": offset 10: malformed dtype field in the .npy header");
}

TEST_CASE("timestamps whose differences could overflow are refused, in every reader", "[io][bad]") {
  namespace h5 = yelan::camera::h5;
  ScratchDir dir("bigt");
  const auto refused = [](const std::string& path) {
    INFO(path);
    CHECK_THROWS_WITH(read_all(path), Catch::StartsWith(path + ": offset ") && Catch::Contains("is outside +-2^60 us"));
  };
  constexpr std::int64_t kBig = 9'000'000'000'000'000'000LL;  // +-9e18 us: their difference overflows int64
  const std::string text = dir.file("big.txt");
  write_text(text, "-9000000000000 1 1 1\n9000000000000 2 2 0\n");  // seconds
  refused(text);
  write_text(text, "1 1 1 1\n2 2 2 0\n");
  CHECK(read_all(text).size() == 2);
  // .npy: a structured array of t, x, y, p.
  std::string dict = "{'descr': [('t', '<i8'), ('x', '<u2'), ('y', '<u2'), ('p', '|u1')], 'fortran_order': False, 'shape': (2,), }";
  while ((10 + dict.size() + 1) % 64) dict += ' ';
  dict += '\n';
  std::vector<unsigned char> npy = {0x93, 'N', 'U', 'M', 'P', 'Y', 1, 0};
  put_le<std::uint16_t>(npy, static_cast<std::uint16_t>(dict.size()));
  npy.insert(npy.end(), dict.begin(), dict.end());
  for (const std::int64_t t : {-kBig, kBig}) {
    put_le<std::int64_t>(npy, t);
    put_le<std::uint16_t>(npy, 1), put_le<std::uint16_t>(npy, 1), npy.push_back(1);
  }
  write_bytes(dir.file("big.npy"), npy);
  refused(dir.file("big.npy"));
  // Ours, as another tool would write it (our writer refuses such a span itself).
  {
    h5::H5Id f = h5::create_file(dir.file("big.yelan.h5"));
    h5::write_attr_string(f.get(), "format", "yelan-recording");
    h5::H5Id g = h5::create_group(f.get(), "events");
    h5_dataset_1d<std::int64_t>(g.get(), "t", H5T_STD_I64LE, H5T_NATIVE_INT64, {-kBig, kBig});
    h5_dataset_1d<std::uint16_t>(g.get(), "x", H5T_STD_U16LE, H5T_NATIVE_UINT16, {1, 2});
    h5_dataset_1d<std::uint16_t>(g.get(), "y", H5T_STD_U16LE, H5T_NATIVE_UINT16, {1, 2});
    h5_dataset_1d<std::uint8_t>(g.get(), "p", H5T_STD_U8LE, H5T_NATIVE_UINT8, {1, 0});
  }
  refused(dir.file("big.yelan.h5"));
  // v2e: one N x 4 dataset.
  {
    h5::H5Id f = h5::create_file(dir.file("big-v2e.h5"));
    const std::vector<std::int64_t> rows = {-kBig, 1, 1, 1, kBig, 2, 2, 0};
    hsize_t dims[2] = {2, 4};
    h5::H5Id space = h5::check(H5Screate_simple(2, dims, nullptr), "space");
    h5::H5Id ds = h5::check(H5Dcreate2(f.get(), "events", H5T_STD_I64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT,
                                       H5P_DEFAULT), "events");
    h5::check(H5Dwrite(ds.get(), H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, rows.data()), "events");
  }
  refused(dir.file("big-v2e.h5"));
  // AEDAT 4.0: int64 timestamps in its event packets.
  {
    auto w = yelan::camera::open_event_writer(dir.file("big.aedat4"), {"", 8, 8, {}, {}});
    const std::vector<Event> ev = {{-kBig, 1, 1, 1}, {kBig, 2, 2, 0}};
    w->write(ev);
    w->close();
  }
  refused(dir.file("big.aedat4"));
  // AEDAT 3.1: a packet's overflow counter of 2^30 puts its events at 2^61 us.
  auto a3 = raw_header("#!AER-DAT3.1\r\n#Format: RAW\r\n#Source 1: DAVIS346\r\n#!END-HEADER\r\n");
  put_le<std::int16_t>(a3, 1), put_le<std::int16_t>(a3, 1);  // polarity packet, source 1
  for (const std::int32_t v : {8, 4, 1 << 30, 1, 1, 1}) put_le<std::int32_t>(a3, v);  // size, ts offset, overflow, counts
  put_le<std::uint32_t>(a3, (7u << 17) | (8u << 2) | (1u << 1) | 1u);                   // x 7, y 8, ON, valid
  put_le<std::int32_t>(a3, 5);
  write_bytes(dir.file("big.aedat"), a3);
  refused(dir.file("big.aedat"));
  // Prophesee RAW (EVT 2/2.1/3) cannot carry them: a timer wrapping past 2^50 us is refused first.
}

TEST_CASE("DSEC HDF5: t_offset near INT64_MAX plus a row's t overflows, refused naming the file", "[io][h5][dsec][bad]") {
  namespace h5 = yelan::camera::h5;
  ScratchDir dir("dsec-overflow");
  const std::string path = dir.file("events.h5");
  {
    h5::H5Id f = h5::create_file(path);
    h5::H5Id g = h5::create_group(f.get(), "events");
    h5_dataset_1d<std::uint16_t>(g.get(), "x", H5T_STD_U16LE, H5T_NATIVE_UINT16, {1, 2});
    h5_dataset_1d<std::uint16_t>(g.get(), "y", H5T_STD_U16LE, H5T_NATIVE_UINT16, {1, 2});
    h5_dataset_1d<std::uint8_t>(g.get(), "p", H5T_STD_U8LE, H5T_NATIVE_UINT8, {1, 0});
    h5_dataset_1d<std::uint32_t>(g.get(), "t", H5T_STD_U32LE, H5T_NATIVE_UINT32, {100, 200});
    h5_dataset_1d<std::uint64_t>(f.get(), "ms_to_idx", H5T_STD_U64LE, H5T_NATIVE_UINT64, {0, 2});
    const std::int64_t t_offset = std::numeric_limits<std::int64_t>::max() - 50;
    h5::H5Id space = h5::check(H5Screate(H5S_SCALAR), "space");
    h5::H5Id ds = h5::check(H5Dcreate2(f.get(), "t_offset", H5T_STD_I64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT,
                                       H5P_DEFAULT), "t_offset");
    h5::check(H5Dwrite(ds.get(), H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, &t_offset), "t_offset");
  }
  // Wrapped (undefined behaviour before the sum was checked), the time came out near INT64_MIN.
  CHECK_THROWS_WITH(read_all(path), Catch::StartsWith(path + ": offset 0: row 0: t 100 + t_offset 9223372036854775757 "
                                                             "overflows 64 bits"));
}
