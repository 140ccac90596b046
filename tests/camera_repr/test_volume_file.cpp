#include <catch2/catch.hpp>
#include <hdf5.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <vector>

#include "camera/repr/preview_png.h"
#include "camera/repr/volume_file.h"

namespace fs = std::filesystem;
using namespace yelan::camera;

namespace {
fs::path temp_dir(const std::string& name) {
  fs::path p = fs::temp_directory_path() / ("yelan_vf_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}
std::size_t entries(const fs::path& dir) {
  return std::size_t(std::distance(fs::directory_iterator(dir), fs::directory_iterator()));
}
}  // namespace

TEST_CASE("volume file: appended volumes and times read back, with attributes", "[volume_file]") {
  const fs::path dir = temp_dir("ok");
  const std::string path = (dir / "v.h5").string();
  {
    VolumeFileWriter w(path, "tore", 2, 3, 5, {{"k", 1}, {"width", 5}});
    std::vector<float> a(30), b(30);
    for (int i = 0; i < 30; ++i) a[i] = float(i), b[i] = -float(i);
    w.append(-7, a.data());
    w.append(1633953690985950, b.data());
    CHECK_FALSE(fs::exists(path));  // not before finish()
    w.finish();
    CHECK(w.count() == 2);
  }
  REQUIRE(fs::exists(path));
  CHECK(entries(dir) == 1);  // no temp file left
  hid_t f = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  REQUIRE(f >= 0);
  hid_t ds = H5Dopen2(f, "volumes", H5P_DEFAULT);
  hid_t sp = H5Dget_space(ds);
  hsize_t dims[4];
  REQUIRE(H5Sget_simple_extent_dims(sp, dims, nullptr) == 4);
  CHECK((dims[0] == 2 && dims[1] == 2 && dims[2] == 3 && dims[3] == 5));
  std::vector<float> all(60);
  H5Dread(ds, H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, all.data());
  CHECK(all[29] == 29.f);
  CHECK(all[59] == -29.f);
  hid_t ts = H5Dopen2(f, "t", H5P_DEFAULT);
  std::int64_t t[2];
  H5Dread(ts, H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, t);
  CHECK(t[0] == -7);
  CHECK(t[1] == 1633953690985950);
  std::int64_t k = 0;
  hid_t attr = H5Aopen(f, "k", H5P_DEFAULT);
  H5Aread(attr, H5T_NATIVE_INT64, &k);
  CHECK(k == 1);
  H5Aclose(attr);
  H5Sclose(sp);
  H5Dclose(ds);
  H5Dclose(ts);
  H5Fclose(f);
  fs::remove_all(dir);
}

TEST_CASE("volume file: abandoned writers leave nothing, an unwritable path names itself", "[volume_file]") {
  const fs::path dir = temp_dir("abandon");
  const std::string path = (dir / "v.h5").string();
  std::ofstream(path) << "old";  // an existing file stays as it was
  {
    VolumeFileWriter w(path, "count", 1, 2, 2);
    const float v[4] = {1, 2, 3, 4};
    w.append(0, v);
  }
  CHECK(entries(dir) == 1);
  std::ifstream in(path);
  std::string s;
  in >> s;
  CHECK(s == "old");
  try {
    VolumeFileWriter w((dir / "no/such/dir/v.h5").string(), "count", 1, 2, 2);
    FAIL("no exception");
  } catch (const std::runtime_error& e) {
    CHECK(std::string(e.what()).find("no/such/dir/v.h5") != std::string::npos);
  }
  CHECK_THROWS_AS(VolumeFileWriter(path, "x", 0, 2, 2), std::runtime_error);
  fs::remove_all(dir);
}

TEST_CASE("previews map channels to colours and PNGs are written atomically", "[volume_file]") {
  // 2x1 volume, 2 channels: ON = {1, 0.5}, OFF = {0, 2}
  const float vol[4] = {1.f, 0.5f, 0.f, 2.f};
  auto rgb = preview_rgb(vol, 2, 1, PreviewStyle::polarity_pair, 0, 1);
  CHECK(rgb == std::vector<std::uint8_t>{255, 0, 0, 128, 0, 255});
  rgb = preview_rgb(vol, 2, 1, PreviewStyle::grey, 0);
  CHECK(rgb == std::vector<std::uint8_t>{255, 255, 255, 128, 128, 128});
  const float signed_vol[2] = {-0.5f, 0.25f};
  rgb = preview_rgb(signed_vol, 2, 1, PreviewStyle::signed_value, 0);
  CHECK(rgb == std::vector<std::uint8_t>{0, 0, 128, 64, 0, 0});
  const fs::path dir = temp_dir("png");
  write_png_rgb((dir / "a.png").string(), 2, 1, rgb);
  CHECK(fs::file_size(dir / "a.png") > 50);
  CHECK(entries(dir) == 1);
  CHECK_THROWS_AS(write_png_rgb((dir / "b.png").string(), 3, 1, rgb), std::runtime_error);
  CHECK_THROWS_AS(write_png_rgb((dir / "missing/c.png").string(), 2, 1, rgb), std::runtime_error);
  CHECK(entries(dir) == 1);
  fs::remove_all(dir);
}
