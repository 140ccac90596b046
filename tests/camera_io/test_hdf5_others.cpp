// DSEC and v2e HDF5 layouts, built here with the HDF5 C API (no public sample in shared data).
#include <catch2/catch.hpp>

#include "camera/io/event_writer.h"
#include "camera/io/h5.h"
#include "io_test_util.h"

using yelan::camera::Event;
namespace h5 = yelan::camera::h5;
using namespace yelan::test;

TEST_CASE("DSEC layout: t relative to t_offset, seek through ms_to_idx", "[io][h5][dsec]") {
  ScratchDir dir("dsec");
  const std::string path = dir.file("events.h5");
  {
    h5::H5Id f = h5::create_file(path);
    h5::H5Id g = h5::create_group(f.get(), "events");
    h5_dataset_1d<std::uint16_t>(g.get(), "x", H5T_STD_U16LE, H5T_NATIVE_UINT16, {1, 639, 5, 7});
    h5_dataset_1d<std::uint16_t>(g.get(), "y", H5T_STD_U16LE, H5T_NATIVE_UINT16, {2, 479, 6, 8});
    h5_dataset_1d<std::uint8_t>(g.get(), "p", H5T_STD_U8LE, H5T_NATIVE_UINT8, {1, 0, 1, 0});
    h5_dataset_1d<std::uint32_t>(g.get(), "t", H5T_STD_U32LE, H5T_NATIVE_UINT32, {10, 999, 1500, 3001});
    // ms_to_idx[k]: first event with t >= 1000 k.
    h5_dataset_1d<std::uint64_t>(f.get(), "ms_to_idx", H5T_STD_U64LE, H5T_NATIVE_UINT64, {0, 2, 3, 3, 4});
    const std::int64_t t_offset = 47'000'000'000LL;
    h5::H5Id space = h5::check(H5Screate(H5S_SCALAR), "space");
    h5::H5Id ds = h5::check(H5Dcreate2(f.get(), "t_offset", H5T_STD_I64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT,
                                       H5P_DEFAULT), "t_offset");
    h5::check(H5Dwrite(ds.get(), H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, &t_offset), "t_offset");
  }
  auto r = yelan::camera::open_event_file(path);
  CHECK(r->info().format == "dsec-h5");
  CHECK(r->info().events == std::optional<std::uint64_t>(4));
  CHECK(r->info().t_first == std::optional<std::int64_t>(47'000'000'010LL));
  CHECK(r->fast_seek());
  const std::int64_t o = 47'000'000'000LL;
  CHECK(read_all(*r) == std::vector<Event>{{o + 10, 1, 2, 1}, {o + 999, 639, 479, 0}, {o + 1500, 5, 6, 1}, {o + 3001, 7, 8, 0}});
  r->seek(o + 1200);
  CHECK(read_all(*r) == std::vector<Event>{{o + 1500, 5, 6, 1}, {o + 3001, 7, 8, 0}});
}

TEST_CASE("v2e layout: one N x 4 dataset of t, x, y, p", "[io][h5][v2e]") {
  ScratchDir dir("v2e");
  const std::string path = dir.file("v2e.h5");
  {
    h5::H5Id f = h5::create_file(path);
    const std::vector<std::int64_t> rows = {100, 3, 4, 1, 105, 345, 259, 0, 105, 0, 0, -1};
    hsize_t dims[2] = {3, 4};
    h5::H5Id space = h5::check(H5Screate_simple(2, dims, nullptr), "space");
    h5::H5Id ds = h5::check(H5Dcreate2(f.get(), "events", H5T_STD_I64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT,
                                       H5P_DEFAULT), "events");
    h5::check(H5Dwrite(ds.get(), H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, rows.data()), "events");
  }
  auto r = yelan::camera::open_event_file(path);
  CHECK(r->info().format == "v2e-h5");
  CHECK(read_all(*r) == std::vector<Event>{{100, 3, 4, 1}, {105, 345, 259, 0}, {105, 0, 0, 0}});
}

TEST_CASE("HDF5 files with mismatched or missing columns are refused", "[io][h5][bad]") {
  ScratchDir dir("h5cols");
  const std::string path = dir.file("bad.h5");
  {
    h5::H5Id f = h5::create_file(path);
    h5::H5Id g = h5::create_group(f.get(), "events");
    h5_dataset_1d<std::uint16_t>(g.get(), "x", H5T_STD_U16LE, H5T_NATIVE_UINT16, {1, 2, 3});
    h5_dataset_1d<std::uint16_t>(g.get(), "y", H5T_STD_U16LE, H5T_NATIVE_UINT16, {1, 2});
    h5_dataset_1d<std::uint8_t>(g.get(), "p", H5T_STD_U8LE, H5T_NATIVE_UINT8, {1, 0, 1});
    h5_dataset_1d<std::int64_t>(g.get(), "t", H5T_STD_I64LE, H5T_NATIVE_INT64, {1, 2, 3});
  }
  CHECK_THROWS_WITH(yelan::camera::open_event_file(path), path + ": offset 0: /events/y has 2 rows but /events/t has 3");
  {
    h5::H5Id f = h5::create_file(path);
    h5::H5Id g = h5::create_group(f.get(), "other");
  }
  CHECK_THROWS_WITH(yelan::camera::open_event_file(path), Catch::Contains("holds no events"));
}

TEST_CASE("our layout written by another tool: variable-length UTF-8 strings, sensor size in /camera only", "[io][h5]") {
  ScratchDir dir("foreign");
  const std::string path = dir.file("foreign.yelan.h5");
  {
    yelan::camera::StreamInfo info;
    info.width = 346, info.height = 260;
    auto w = yelan::camera::open_yelan_h5_writer(path, info);
    const std::vector<Event> ev = {{10, 1, 2, 1}, {20, 345, 259, 0}, {30, 7, 8, 1}};
    w->write(ev);
    w->close();
  }
  {
    // As h5py writes `f.attrs['format'] = 'yelan-recording'` (a variable-length UTF-8 string),
    // with the sensor size in /camera/{width,height} (SPEC 2) and no root width/height.
    h5::H5Id f = h5::check(H5Fopen(path.c_str(), H5F_ACC_RDWR, H5P_DEFAULT), "open");
    for (const char* a : {"format", "width", "height"})
      if (H5Aexists(f.get(), a) > 0) H5Adelete(f.get(), a);
    h5::H5Id type = h5::check(H5Tcopy(H5T_C_S1), "type");
    H5Tset_size(type.get(), H5T_VARIABLE);
    H5Tset_cset(type.get(), H5T_CSET_UTF8);
    h5::H5Id space = h5::check(H5Screate(H5S_SCALAR), "space");
    h5::H5Id attr = h5::check(H5Acreate2(f.get(), "format", type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT), "attr");
    const char* text = "yelan-recording";
    h5::check(H5Awrite(attr.get(), type.get(), &text), "write attr");
    h5::H5Id cam = h5::create_group(f.get(), "camera");
    for (const auto& [name, v] : {std::pair<const char*, std::int64_t>{"width", 346}, {"height", 260}}) {
      h5::H5Id s = h5::check(H5Screate(H5S_SCALAR), "space");
      h5::H5Id d = h5::check(H5Dcreate2(cam.get(), name, H5T_STD_I64LE, s.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), name);
      h5::check(H5Dwrite(d.get(), H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, &v), name);
    }
  }
  auto r = yelan::camera::open_event_file(path);
  CHECK(r->info().format == "yelan-h5");
  CHECK(r->info().width == 346);
  CHECK(r->info().height == 260);
  CHECK(read_all(*r).size() == 3);
}
