// RawChunkReader (chunks read as stored, inflated outside HDF5's lock) against H5Dread, and
// the yelan-h5 event reader that goes through it.
#include <catch2/catch.hpp>

#include <cstring>
#include <random>

#include "camera/io/event_writer.h"
#include "camera/io/h5.h"
#include "camera/io/h5_chunks.h"
#include "io_test_util.h"

using yelan::camera::Event;
namespace h5 = yelan::camera::h5;
using namespace yelan::test;

namespace {

enum class Filters { none, deflate, shuffle_deflate, fletcher };

// A chunked dataset of `dims` holding `v`, created with `filters`.
template <typename T>
h5::H5Id chunked(hid_t loc, const char* name, hid_t type, hid_t mem, std::vector<hsize_t> dims, std::vector<hsize_t> chunk,
                 Filters filters, const std::vector<T>& v) {
  h5::H5Id space = h5::check(H5Screate_simple(int(dims.size()), dims.data(), nullptr), "space");
  h5::H5Id props = h5::check(H5Pcreate(H5P_DATASET_CREATE), "props");
  h5::check(H5Pset_chunk(props.get(), int(chunk.size()), chunk.data()), "chunk");
  if (filters == Filters::shuffle_deflate) h5::check(H5Pset_shuffle(props.get()), "shuffle");
  if (filters == Filters::deflate || filters == Filters::shuffle_deflate) h5::check(H5Pset_deflate(props.get(), 4), "deflate");
  if (filters == Filters::fletcher) h5::check(H5Pset_fletcher32(props.get()), "fletcher32");
  h5::H5Id ds = h5::check(H5Dcreate2(loc, name, type, space.get(), H5P_DEFAULT, props.get(), H5P_DEFAULT), name);
  if (!v.empty()) h5::check(H5Dwrite(ds.get(), mem, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()), name);
  return ds;
}

void write_yelan_h5(const std::string& path, const std::vector<Event>& ev) {
  yelan::camera::StreamInfo info;
  info.width = 346;
  info.height = 260;
  auto w = yelan::camera::open_yelan_h5_writer(path, info);
  w->write(ev);
  w->close();
}

template <typename T>
std::vector<T> as(const std::vector<unsigned char>& bytes, std::size_t n) {
  std::vector<T> out(n);
  std::memcpy(out.data(), bytes.data(), n * sizeof(T));
  return out;
}

}  // namespace

TEST_CASE("raw chunks inflated here equal H5Dread's values", "[io][h5][chunks]") {
  ScratchDir dir("h5chunks");
  h5::H5Id f = h5::create_file(dir.file("c.h5"));
  std::mt19937 rng(7);
  std::vector<std::int16_t> smooth(2500);  // a partial last chunk
  for (std::size_t i = 0; i < smooth.size(); ++i) smooth[i] = std::int16_t(int(i % 700) - 350);
  std::vector<std::uint64_t> noise(1200);  // deflate cannot shrink it
  for (auto& v : noise) v = (std::uint64_t(rng()) << 32) | rng();

  SECTION("shuffle then deflate, int16") {
    h5::H5Id ds = chunked(f.get(), "s", H5T_STD_I16LE, H5T_NATIVE_INT16, {2500}, {1000}, Filters::shuffle_deflate, smooth);
    REQUIRE(h5::RawChunkReader::suits(ds.get()));
    h5::RawChunkReader r(ds.get());
    CHECK(r.chunk_bytes() == 2000);
    std::vector<unsigned char> bytes;
    for (hsize_t c = 0; c < 3; ++c) {
      const hsize_t at = c * 1000;
      REQUIRE(r.read(ds.get(), &at, bytes));
      const std::size_t n = std::min<std::size_t>(1000, smooth.size() - at);
      const std::vector<std::int16_t> want(smooth.begin() + long(at), smooth.begin() + long(at + n));
      const bool same = as<std::int16_t>(bytes, n) == want;
      CHECK(same);
    }
  }
  SECTION("deflate that expands the chunk, uint64") {
    h5::H5Id ds = chunked(f.get(), "n", H5T_STD_U64LE, H5T_NATIVE_UINT64, {1200}, {600}, Filters::deflate, noise);
    h5::RawChunkReader r(ds.get());
    std::vector<unsigned char> bytes;
    const hsize_t at = 600;
    REQUIRE(r.read(ds.get(), &at, bytes));
    CHECK(as<std::uint64_t>(bytes, 600) == std::vector<std::uint64_t>(noise.begin() + 600, noise.end()));
  }
  SECTION("2-D chunks of one row (masks), uint8, no filter and deflate") {
    std::vector<std::uint8_t> masks(3 * 5 * 7);
    for (std::size_t i = 0; i < masks.size(); ++i) masks[i] = std::uint8_t(i * 37 % 251);
    for (Filters filters : {Filters::none, Filters::deflate}) {
      const char* name = filters == Filters::none ? "plain" : "deflated";
      h5::H5Id ds = chunked(f.get(), name, H5T_STD_U8LE, H5T_NATIVE_UINT8, {3, 5, 7}, {1, 5, 7}, filters, masks);
      h5::RawChunkReader r(ds.get());
      std::vector<unsigned char> bytes;
      const hsize_t at[3] = {2, 0, 0};
      REQUIRE(r.read(ds.get(), at, bytes));
      CHECK(bytes == std::vector<unsigned char>(masks.begin() + 70, masks.end()));
    }
  }
  SECTION("a chunk never written reads as not there") {
    h5::H5Id ds = chunked(f.get(), "sparse", H5T_STD_I32LE, H5T_NATIVE_INT32, {3000}, {1000}, Filters::deflate,
                          std::vector<std::int32_t>{});
    const std::vector<std::int32_t> first(1000, 5);
    const hsize_t start = 0, count = 1000;
    h5::H5Id fs = h5::check(H5Dget_space(ds.get()), "space");
    h5::check(H5Sselect_hyperslab(fs.get(), H5S_SELECT_SET, &start, nullptr, &count, nullptr), "select");
    h5::H5Id ms = h5::check(H5Screate_simple(1, &count, nullptr), "space");
    h5::check(H5Dwrite(ds.get(), H5T_NATIVE_INT32, ms.get(), fs.get(), H5P_DEFAULT, first.data()), "write");
    h5::RawChunkReader r(ds.get());
    std::vector<unsigned char> bytes;
    hsize_t at = 0;
    CHECK(r.read(ds.get(), &at, bytes));
    at = 2000;
    CHECK_FALSE(r.read(ds.get(), &at, bytes));
  }
  SECTION("a stored chunk that does not inflate is refused") {
    h5::H5Id ds = chunked(f.get(), "bad", H5T_STD_I16LE, H5T_NATIVE_INT16, {1000}, {1000}, Filters::deflate,
                          std::vector<std::int16_t>{});
    const std::vector<unsigned char> garbage(300, 0xab);
    const hsize_t at = 0;
    h5::check(H5Dwrite_chunk(ds.get(), H5P_DEFAULT, 0, &at, garbage.size(), garbage.data()), "write chunk");
    h5::RawChunkReader r(ds.get());
    std::vector<unsigned char> bytes;
    CHECK_THROWS_AS(r.read(ds.get(), &at, bytes), h5::H5Failure);
  }
  SECTION("other pipelines, padded integers and big-endian ones are left to H5Dread") {
    h5::H5Id fl = chunked(f.get(), "f", H5T_STD_I16LE, H5T_NATIVE_INT16, {2500}, {1000}, Filters::fletcher, smooth);
    CHECK_FALSE(h5::RawChunkReader::suits(fl.get()));
    CHECK_THROWS_AS(h5::RawChunkReader(fl.get()), h5::H5Failure);
    h5::H5Id be = chunked(f.get(), "be", H5T_STD_I16BE, H5T_NATIVE_INT16, {2500}, {1000}, Filters::deflate, smooth);
    CHECK_FALSE(h5::RawChunkReader::suits(be.get()));
    h5::H5Id t12 = h5::check(H5Tcopy(H5T_STD_I16LE), "type");
    h5::check(H5Tset_precision(t12.get(), 12), "precision");
    h5::H5Id p12 = chunked(f.get(), "p12", t12.get(), H5T_NATIVE_INT16, {2500}, {1000}, Filters::deflate, smooth);
    CHECK_FALSE(h5::RawChunkReader::suits(p12.get()));
    const hsize_t four = 4;
    h5::H5Id space = h5::check(H5Screate_simple(1, &four, nullptr), "space");
    h5::H5Id contiguous =
        h5::check(H5Dcreate2(f.get(), "c", H5T_STD_I16LE, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), "c");
    CHECK_FALSE(h5::RawChunkReader::suits(contiguous.get()));
  }
}

TEST_CASE("yelan-h5 events across chunks read back whole and after seeks inside a chunk", "[io][h5][chunks]") {
  ScratchDir dir("h5chunk_events");
  const std::string path = dir.file("ev.h5");
  std::vector<Event> ev;
  std::mt19937 rng(3);
  std::int64_t t = 1'000'000;
  for (int i = 0; i < 200'000; ++i) {  // four chunks of 64Ki rows, the last partial
    t += rng() % 9;
    ev.push_back({t, std::uint16_t(rng() % 346), std::uint16_t(rng() % 260), std::uint8_t(rng() & 1)});
  }
  write_yelan_h5(path, ev);
  auto r = yelan::camera::open_event_file(path);
  REQUIRE(r->fast_seek());
  const bool whole = read_all(*r, 50'000) == ev;
  CHECK(whole);
  // Seek forward inside chunk 2, then back inside chunk 0: each reads on across chunks.
  for (std::size_t at : {std::size_t(150'001), std::size_t(20'000), std::size_t(131'072)}) {
    r->seek(ev[at].t);
    const auto first = std::lower_bound(ev.begin(), ev.end(), ev[at].t, [](const Event& e, std::int64_t tt) { return e.t < tt; });
    const bool tail = read_all(*r, 30'000) == std::vector<Event>(first, ev.end());
    CHECK(tail);
  }
}

TEST_CASE("a yelan-h5 event chunk that does not inflate names its rows", "[io][h5][chunks][bad]") {
  ScratchDir dir("h5chunk_bad");
  const std::string path = dir.file("ev.h5");
  std::vector<Event> ev;
  for (int i = 0; i < 70'000; ++i) ev.push_back({1000 + i, std::uint16_t(i % 300), std::uint16_t(i % 200), std::uint8_t(i & 1)});
  write_yelan_h5(path, ev);
  {
    h5::H5Id f = h5::check(H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT), "open");
    h5::H5Id x = h5::check(H5Dopen2(f.get(), "events/x", H5P_DEFAULT), "x");
    const std::vector<unsigned char> garbage(500, 0x5a);
    const hsize_t at = 65536;
    h5::check(H5Dwrite_chunk(x.get(), H5P_DEFAULT, 0, &at, garbage.size(), garbage.data()), "write chunk");
  }
  auto r = yelan::camera::open_event_file(path);
  std::vector<Event> got;
  try {
    while (r->read(got, 10'000) > 0) {
    }
    FAIL("read past a corrupt chunk");
  } catch (const yelan::camera::FormatError& e) {
    CHECK_THAT(e.what(), Catch::Contains("rows 65536..70000"));
  }
  CHECK(got.size() == 65536);
}
