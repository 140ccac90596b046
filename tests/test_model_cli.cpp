// `yelan weights init` and `yelan model summary|forward` through the CLI.
#include <catch2/catch.hpp>
#include <hdf5.h>
#include <unistd.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "engine/cli/cli.h"
#include "cli_util.h"

namespace {

using Result = yelan::test::CliResult;
Result cli(std::vector<std::string> argv) { return yelan::test::run_cli(std::move(argv)); }
bool has(const std::string& s, const std::string& w) { return yelan::test::contains(s, w); }
using yelan::test::slurp;
struct TempDir : yelan::test::CliTempDir {
  TempDir() : CliTempDir("model") {}
};

std::vector<float> read_all(const std::string& file, const std::string& name, std::vector<hsize_t>& dims) {
  const hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  REQUIRE(f >= 0);
  const hid_t d = H5Dopen2(f, name.c_str(), H5P_DEFAULT);
  REQUIRE(d >= 0);
  const hid_t sp = H5Dget_space(d);
  dims.resize(H5Sget_simple_extent_ndims(sp));
  H5Sget_simple_extent_dims(sp, dims.data(), nullptr);
  std::size_t n = 1;
  for (auto v : dims) n *= v;
  std::vector<float> out(n);
  REQUIRE(H5Dread(d, H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) >= 0);
  H5Sclose(sp);
  H5Dclose(d);
  H5Fclose(f);
  return out;
}

}  // namespace

TEST_CASE("yelan weights init writes a verifiable, reproducible weights file", "[cli][model]") {
  TempDir dir;
  const Result r = cli({"weights", "init", "--config", "tiny", "--seed", "3", "-o", dir / "a.h5"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(has(r.out, "wrote"));
  CHECK(cli({"weights", "verify", dir / "a.h5", "--config", "tiny"}).code == 0);
  REQUIRE(cli({"weights", "init", "--config", "tiny", "--seed", "3", "-o", dir / "b.h5"}).code == 0);
  CHECK(slurp(dir / "a.h5") == slurp(dir / "b.h5"));  // same seed, same bytes
  REQUIRE(cli({"weights", "init", "--config", "tiny", "--seed", "4", "-o", dir / "c.h5"}).code == 0);
  CHECK(cli({"weights", "diff", dir / "a.h5", dir / "c.h5"}).code == 1);  // another seed differs
  const Result bad = cli({"weights", "init", "--config", "no-such", "--seed", "1", "-o", dir / "d.h5"});
  CHECK(bad.code == 2);
  CHECK(has(bad.err, "no config 'no-such'"));
  CHECK_FALSE(std::filesystem::exists(dir / "d.h5"));
}

TEST_CASE("yelan model summary counts the reference's parameters", "[cli][model]") {
  const Result r = cli({"model", "summary", "--config", "paper", "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(has(r.out, "\"params_pose\": 20390199"));
  CHECK(has(r.out, "\"params_mask\": 31196768"));
  CHECK(has(r.out, "\"flops_per_pose\": "));
  CHECK(has(r.out, "\"module\": \"in_cnn\""));
  // per layer: the ResNet stem, as the reference names it, with its shapes and FLOPs
  CHECK(has(r.out, "{\"net\": \"pose\", \"name\": \"in_cnn.0\", \"type\": \"conv7x7/2\", \"in\": [6, 260, 346], "
                   "\"out\": [64, 130, 173], \"params\": 18816, \"flops\": 846343680"));
  CHECK(has(r.out, "\"name\": \"up1.up\", \"type\": \"deconv2x2/2\""));
  CHECK(has(r.out, "\"peak_bytes_inference\": "));
  const Result t = cli({"model", "summary", "--config", "tiny"});
  CHECK(t.code == 0);
  CHECK(has(t.out, "pose net: 246550 parameters"));
  CHECK(has(t.out, "pose in_cnn.0"));
  CHECK(has(t.out, "conv7x7/2    6x37x75"));
  CHECK(cli({"model", "summary"}).code == 2);
  CHECK(cli({"model", "frob"}).code == 2);
}

TEST_CASE("yelan model summary counts stage 1 twice under run.mask_mirror, and says so", "[cli][model]") {
  const std::string dir = std::string(YELAN_SOURCE_DIR) + "/benchmarks/configs/";
  const std::string plain = dir + "small-mask0.375-pose0.125-masked-reuse-b094-crop8-s41.json",
                    mirror = dir + "small-mask0.375-pose0.125-masked-reuse-b094-crop8-s42-mirror.json";
  auto flops_per_mask = [](const std::string& json) {
    const auto at = json.find("\"flops_per_mask\": ");
    REQUIRE(at != std::string::npos);
    return std::stod(json.substr(at + 18));
  };
  const Result p = cli({"model", "summary", "--config", plain, "--json"}), m = cli({"model", "summary", "--config", mirror, "--json"});
  INFO(p.err << m.err);
  REQUIRE((p.code == 0 && m.code == 0));
  CHECK(flops_per_mask(m.out) == 2 * flops_per_mask(p.out));
  CHECK(has(cli({"model", "summary", "--config", mirror}).out, "stage 1 runs twice a frame"));
  CHECK_FALSE(has(cli({"model", "summary", "--config", plain}).out, "stage 1 runs twice a frame"));
}

TEST_CASE("yelan model forward writes every head for an input window", "[cli][model]") {
  TempDir dir;
  REQUIRE(cli({"weights", "init", "--config", "tiny", "--seed", "5", "-o", dir / "w.h5"}).code == 0);
  // tiny: window 3, 6 x 37 x 75
  {
    const hid_t f = H5Fcreate((dir / "in.h5").c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    const hsize_t dims[4] = {3, 6, 37, 75};
    const hid_t sp = H5Screate_simple(4, dims, nullptr);
    const hid_t d = H5Dcreate2(f, "input", H5T_NATIVE_FLOAT, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    std::vector<float> x(3 * 6 * 37 * 75);
    for (std::size_t i = 0; i < x.size(); ++i) x[i] = float(std::fmod(i * 0.618034, 1.0));
    H5Dwrite(d, H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, x.data());
    H5Dclose(d);
    H5Sclose(sp);
    H5Fclose(f);
  }
  const Result r = cli({"model", "forward", "--weights", dir / "w.h5", "--input", dir / "in.h5", "--output", dir / "out.h5"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  std::vector<hsize_t> dims;
  read_all(dir / "out.h5", "masks", dims);
  CHECK(dims == std::vector<hsize_t>{3, 4, 37, 75});
  const auto scores = read_all(dir / "out.h5", "scores", dims);
  CHECK(dims == std::vector<hsize_t>{3, 4});
  for (float s : scores) CHECK((s > 0.f && s < 1.f));
  const auto hm = read_all(dir / "out.h5", "heatmaps/stage1/zy", dims);
  REQUIRE(dims.size() == 4);
  double sum = 0;
  for (hsize_t i = 0; i < dims[2] * dims[3]; ++i) sum += hm[i];
  CHECK(sum == Approx(1.0).epsilon(1e-4));
  read_all(dir / "out.h5", "joints_norm", dims);
  CHECK(dims == std::vector<hsize_t>{3, 13, 3});
  // a window that does not fit the config is bad input
  const Result bad = cli({"model", "forward", "--weights", dir / "w.h5", "--input", dir / "w.h5", "--output", dir / "x.h5"});
  CHECK(bad.code == 2);
  CHECK_FALSE(std::filesystem::exists(dir / "x.h5"));
  // so is a window claiming millions of frames, or 2^32 + 6 channels (never written: the
  // files stay small)
  const auto unwritten = [&](const char* name, std::array<hsize_t, 4> dims) {
    const hid_t f = H5Fcreate((dir / name).c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    const hid_t sp = H5Screate_simple(4, dims.data(), nullptr);
    H5Dclose(H5Dcreate2(f, "input", H5T_NATIVE_FLOAT, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
    H5Sclose(sp);
    H5Fclose(f);
    REQUIRE(std::filesystem::file_size(dir / name) < 100000);
  };
  unwritten("huge.h5", {3ull << 20, 6, 37, 75});
  const Result huge = cli({"model", "forward", "--weights", dir / "w.h5", "--input", dir / "huge.h5", "--output", dir / "y.h5"});
  CHECK(huge.code == 2);
  CHECK(has(huge.err, "3145728 frames"));
  CHECK(has(huge.err, "at most 1024"));
  unwritten("wide.h5", {3, (1ull << 32) + 6, 37, 75});
  const Result wide = cli({"model", "forward", "--weights", dir / "w.h5", "--input", dir / "wide.h5", "--output", dir / "y.h5"});
  CHECK(wide.code == 2);
  CHECK(has(wide.err, "input must be S x 6 x 37 x 75"));
  CHECK_FALSE(std::filesystem::exists(dir / "y.h5"));
}

TEST_CASE("yelan bench networks refuses bad usage", "[cli][model]") {
  const Result r = cli({"bench", "networks", "--configs", "no-such"});
  CHECK(r.code == 2);
  CHECK(has(r.err, "no config 'no-such'"));
  CHECK(cli({"bench", "networks", "--threads-list", "0"}).code == 2);
  CHECK(cli({"bench", "nothing"}).code == 2);
}
