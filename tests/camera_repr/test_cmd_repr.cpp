#include <catch2/catch.hpp>
#include <hdf5.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>

#include "camera/io/event_reader.h"
#include "engine/cli/cli.h"
#include "test_util.h"
#include "cli_util.h"

namespace fs = std::filesystem;

namespace {

using Result = yelan::test::CliResult;
Result yelan_cli(std::vector<std::string> argv) { return yelan::test::run_cli(std::move(argv)); }
bool has(const std::string& s, const std::string& what) { return yelan::test::contains(s, what); }

// A fresh directory per test case, removed at the end.
struct TempDir {
  fs::path path;
  explicit TempDir(const std::string& name)
      : path(fs::temp_directory_path() / ("yelan_repr_" + name + "_" + std::to_string(::getpid()))) {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  std::string operator/(const std::string& f) const { return (path / f).string(); }
};

struct Volumes {
  std::vector<hsize_t> dims;
  std::vector<float> data;
  std::vector<std::int64_t> t;
  float at(std::size_t n, std::size_t c, std::size_t y, std::size_t x) const {
    return data[((n * dims[1] + c) * dims[2] + y) * dims[3] + x];
  }
};

Volumes read_volumes(const std::string& path) {
  Volumes v;
  hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  REQUIRE(f >= 0);
  hid_t ds = H5Dopen2(f, "volumes", H5P_DEFAULT);
  hid_t sp = H5Dget_space(ds);
  REQUIRE(H5Sget_simple_extent_ndims(sp) == 4);
  v.dims.resize(4);
  H5Sget_simple_extent_dims(sp, v.dims.data(), nullptr);
  v.data.resize(v.dims[0] * v.dims[1] * v.dims[2] * v.dims[3]);
  if (!v.data.empty()) REQUIRE(H5Dread(ds, H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data.data()) >= 0);
  H5Sclose(sp);
  H5Dclose(ds);
  hid_t ts = H5Dopen2(f, "t", H5P_DEFAULT);
  v.t.resize(v.dims[0]);
  if (!v.t.empty()) REQUIRE(H5Dread(ts, H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.t.data()) >= 0);
  H5Dclose(ts);
  H5Fclose(f);
  return v;
}

double yelan_value(double age, double tau = 5e6) {
  return std::clamp(1 - std::log1p(age) / std::log(tau), 0.0, 0.7) / 0.7;
}

void write_text(const std::string& path, const std::string& body) {
  std::ofstream(path) << "# t_us x y p\n# geometry 5x3\n" << body;
}

bool no_temp_files(const fs::path& dir) {
  for (const auto& e : fs::directory_iterator(dir))
    if (has(e.path().filename().string(), ".tmp-")) return false;
  return true;
}

}  // namespace

TEST_CASE("yelan repr --type tore writes hand-checkable volumes, times and pictures", "[cmd_repr]") {
  TempDir dir("tore");
  write_text(dir / "in.txt", "100 2 1 1\n200 2 1 1\n300 2 1 1\n400 2 1 1\n1000 4 2 0\n5000 0 0 1\n");
  Result r = yelan_cli({"repr", "--type", "tore", "--at", "1100,6000", dir / "in.txt", dir / "out.h5",
                        "--png", dir / "png"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(has(r.out, "2 volume(s) of 6x3x5"));
  Volumes v = read_volumes(dir / "out.h5");
  REQUIRE(v.dims == std::vector<hsize_t>{2, 6, 3, 5});
  CHECK(v.t == std::vector<std::int64_t>{1100, 6000});
  CHECK(v.at(0, 0, 1, 2) == Approx(yelan_value(700)).margin(2e-6));
  CHECK(v.at(0, 1, 1, 2) == Approx(yelan_value(800)).margin(2e-6));
  CHECK(v.at(0, 2, 1, 2) == Approx(yelan_value(900)).margin(2e-6));
  CHECK(v.at(0, 3, 2, 4) == 1.f);        // age 100
  CHECK(v.at(0, 0, 0, 0) == 0.f);        // the event at 5000 is not in the volume at 1100
  CHECK(v.at(1, 0, 0, 0) == Approx(yelan_value(1000)).margin(2e-6));
  CHECK(v.at(1, 3, 2, 4) == Approx(yelan_value(5000)).margin(2e-6));
  for (const char* name : {"000000.png", "000001.png"}) {
    std::ifstream png(dir / ("png/" + std::string(name)), std::ios::binary);
    REQUIRE(png.good());
    unsigned char head[24] = {};
    png.read(reinterpret_cast<char*>(head), 24);
    CHECK(head[1] == 'P');
    CHECK(head[2] == 'N');
    CHECK(head[19] == 5);  // IHDR width, big-endian
    CHECK(head[23] == 3);  // IHDR height
  }
  CHECK(no_temp_files(dir.path));
}

TEST_CASE("yelan repr --type count, voxel and surface over a generated stream", "[cmd_repr]") {
  TempDir dir("baselines");
  write_text(dir / "in.txt", "0 0 0 1\n10 1 0 1\n10 1 0 0\n20 1 0 1\n30 2 1 0\n");
  // constant count: the last 2 events at T = 30 are (1,0) at 20 and (2,1) at 30: both 1 -> 1
  Result r = yelan_cli({"repr", "--type", "count", "--events", "2", "--at", "30", dir / "in.txt", dir / "c.h5"});
  REQUIRE(r.code == 0);
  Volumes c = read_volumes(dir / "c.h5");
  REQUIRE(c.dims == std::vector<hsize_t>{1, 1, 3, 5});
  CHECK(c.at(0, 0, 0, 1) == 1.f);
  CHECK(c.at(0, 0, 1, 2) == 1.f);
  CHECK(c.at(0, 0, 0, 0) == 0.f);
  // constant time, window 25 us at T = 30: events with t in (5, 30]: (1,0) x3, (2,1) x1
  r = yelan_cli({"repr", "--type", "count", "--window-us", "25", "--at", "30", dir / "in.txt", dir / "t.h5"});
  REQUIRE(r.code == 0);
  Volumes t = read_volumes(dir / "t.h5");
  const double three_sigma = 3 * 1.0;  // counts {3, 1}: sigma 1
  CHECK(t.at(0, 0, 0, 1) == 1.f);      // 3 / 3 sigma = 1
  CHECK(t.at(0, 0, 1, 2) == Approx(1 / three_sigma));
  CHECK(t.at(0, 0, 0, 0) == 0.f);
  // voxel: 3 bins over (T - 20, T] = [10, 30]; (1,0): +1 at u=0, -1 at u=0, +1 at u=1
  r = yelan_cli({"repr", "--type", "voxel", "--bins", "3", "--window-us", "20", "--at", "30", dir / "in.txt",
                 dir / "v.h5"});
  REQUIRE(r.code == 0);
  Volumes v = read_volumes(dir / "v.h5");
  REQUIRE(v.dims == std::vector<hsize_t>{1, 3, 3, 5});
  CHECK(v.at(0, 0, 0, 1) == Approx(0.0));
  CHECK(v.at(0, 1, 0, 1) == Approx(1.0));
  CHECK(v.at(0, 2, 1, 2) == Approx(-1.0));
  // time surface, tau 10 us at T = 30
  r = yelan_cli({"repr", "--type", "surface", "--tau-us", "10", "--at", "30", dir / "in.txt", dir / "s.h5"});
  REQUIRE(r.code == 0);
  Volumes s = read_volumes(dir / "s.h5");
  REQUIRE(s.dims == std::vector<hsize_t>{1, 2, 3, 5});
  CHECK(s.at(0, 0, 0, 1) == Approx(std::exp(-1.0)));
  CHECK(s.at(0, 1, 0, 1) == Approx(std::exp(-2.0)));
  CHECK(s.at(0, 1, 1, 2) == Approx(1.0));
  CHECK(s.at(0, 0, 0, 0) == Approx(std::exp(-3.0)));
}

TEST_CASE("yelan repr --fps starts one period after the first event and stops at the last", "[cmd_repr]") {
  TempDir dir("fps");
  write_text(dir / "in.txt", "1000 0 0 1\n1500 1 1 0\n3999 2 2 1\n");
  Result r = yelan_cli({"repr", "--type", "tore", "--k", "1", "--fps", "1000", dir / "in.txt", dir / "o.h5"});
  REQUIRE(r.code == 0);
  Volumes v = read_volumes(dir / "o.h5");
  CHECK(v.t == std::vector<std::int64_t>{2000, 3000});
  REQUIRE(v.dims == std::vector<hsize_t>{2, 2, 3, 5});
  CHECK(v.at(0, 1, 1, 1) == Approx(yelan_value(500)).margin(2e-6));
  CHECK(v.at(1, 0, 2, 2) == 0.f);  // 3999 is after the last volume
}

TEST_CASE("yelan repr: bad usage and bad input exit 2 and leave no output", "[cmd_repr]") {
  TempDir dir("bad");
  write_text(dir / "in.txt", "0 0 0 1\n");
  const std::string in = dir / "in.txt", out = dir / "o.h5";
  struct Case {
    std::vector<std::string> argv;
    const char* says;
  };
  for (const Case& c : std::vector<Case>{
           {{"repr", "--at", "1", in, out}, "--type expects"},
           {{"repr", "--type", "frames", "--at", "1", in, out}, "got 'frames'"},
           {{"repr", "--type", "tore", in, out}, "exactly one of --at"},
           {{"repr", "--type", "tore", "--at", "1", "--fps", "2", in, out}, "exactly one of --at"},
           {{"repr", "--type", "tore", "--at", "5,3", in, out}, "increasing order"},
           {{"repr", "--type", "tore", "--at", "1,x", in, out}, "--at expects an integer"},
           {{"repr", "--type", "tore", "--fps", "0", in, out}, "--fps expects"},
           {{"repr", "--type", "tore", "--k", "0", "--at", "1", in, out}, "--k expects"},
           {{"repr", "--type", "count", "--k", "2", "--at", "1", in, out}, "--k applies"},
           {{"repr", "--type", "tore", "--at", "1", in}, "expected 2 argument"},
           {{"repr", "--type", "tore", "--at", "1", dir / "missing.txt", out}, "missing.txt"},
       }) {
    INFO(c.says);
    Result r = yelan_cli(c.argv);
    CHECK(r.code == 2);
    CHECK(has(r.err, c.says));
  }
  // a file that is not an event file: the error names it, OUT is never created
  std::ofstream(dir / "junk.aedat4", std::ios::binary) << "#!AER-DAT4.0\r\n\x01\x02garbage";
  Result r = yelan_cli({"repr", "--type", "tore", "--at", "1", dir / "junk.aedat4", out});
  CHECK(r.code == 2);
  CHECK(has(r.err, "junk.aedat4"));
  CHECK_FALSE(fs::exists(out));
  CHECK(no_temp_files(dir.path));
  // no sensor size in the file and none given
  std::ofstream(dir / "nosize.txt") << "# t_us x y p\n0 1 1 1\n";
  r = yelan_cli({"repr", "--type", "tore", "--at", "1", dir / "nosize.txt", out});
  CHECK(r.code == 2);
  CHECK(has(r.err, "--width and --height"));
  r = yelan_cli({"repr", "--type", "tore", "--at", "1", "--width", "2", "--height", "2", dir / "nosize.txt", out});
  CHECK(r.code == 0);
  CHECK(read_volumes(out).at(0, 0, 1, 1) == 1.f);
}

TEST_CASE("yelan repr --fps refuses to write more than --max-volumes volumes", "[cmd_repr]") {
  TempDir dir("max");
  write_text(dir / "in.txt", "0 0 0 1\n10000000000 1 1 1\n");  // a timestamp 10^4 s later
  Result r = yelan_cli({"repr", "--type", "surface", "--fps", "1", "--max-volumes", "5", dir / "in.txt", dir / "o.h5"});
  CHECK(r.code == 1);
  CHECK(has(r.err, "more than 5 volumes"));
  CHECK_FALSE(fs::exists(dir / "o.h5"));
  CHECK(no_temp_files(dir.path));
  r = yelan_cli({"repr", "--type", "surface", "--fps", "1", "--max-volumes", "5", "--at", "1", dir / "in.txt", dir / "o.h5"});
  CHECK(r.code == 2);
}

TEST_CASE("yelan repr on the DAVIS346 AEDAT4 sample: 12 volumes at 100 fps over its 130 ms", "[cmd_repr]") {
  const std::string in = yelan::test::shared_data_or_skip("events/aestream_davis.aedat4");
  TempDir dir("davis");
  Result r = yelan_cli({"repr", "--type", "tore", "--fps", "100", in, dir / "davis.h5", "--png", dir / "png"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(has(r.out, "from 117667 events"));  // the data README's count
  Volumes v = read_volumes(dir / "davis.h5");
  REQUIRE(v.dims == std::vector<hsize_t>{12, 6, 260, 346});
  const std::int64_t t_first = 1633953690975950;  // README: first and last event times
  CHECK(v.t.front() == t_first + 10'000);
  CHECK(v.t.back() == t_first + 120'000);           // the last event is at t_first + 129,999
  // Independently: the pixels with an ON (OFF) event up to the last read-out are exactly
  // the pixels whose pos0 (neg0) is non-zero (every age there is far below 5 s).
  std::set<int> on, off;
  auto reader = yelan::camera::open_event_file(in);
  std::vector<yelan::camera::Event> batch;
  while (reader->read(batch, 1 << 16)) {
    for (const auto& e : batch)
      if (e.t <= v.t.back()) (e.p ? on : off).insert(e.y * 346 + e.x);
    batch.clear();
  }
  std::size_t lit_on = 0, lit_off = 0;
  for (std::size_t i = 0; i < 260 * 346; ++i) {
    lit_on += v.at(11, 0, i / 346, i % 346) > 0.f;
    lit_off += v.at(11, 3, i / 346, i % 346) > 0.f;
  }
  CHECK(lit_on == on.size());
  CHECK(lit_off == off.size());
  CHECK(lit_on > 1000);
  CHECK(fs::exists(dir / "png/000011.png"));
  CHECK_FALSE(fs::exists(dir / "png/000012.png"));
}
