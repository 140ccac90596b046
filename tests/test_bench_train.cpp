// `yelan bench train` through the CLI: what it reports and the batches it hands to PyTorch;
// the sweep charts' labels.
// No timing is asserted (tests never time); the micro config keeps each run to seconds.
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "benchmarks/run/xy_chart.h"
#include "camera/io/h5.h"
#include "cli_util.h"

namespace {

namespace h5 = yelan::camera::h5;
using yelan::test::run_cli;

// Two procedural dances: no CMU clips needed, so the test runs without ../shared.
const char* kScenes = "ben-dance3-front-high-static,lena-dance4-left-medium-dynamic";

std::vector<float> read(hid_t f, const std::string& name, std::vector<hsize_t>& dims) {
  h5::H5Id ds = h5::check(H5Dopen2(f, name.c_str(), H5P_DEFAULT), "open " + name);
  dims = h5::shape(ds.get());
  std::size_t n = 1;
  for (auto d : dims) n *= d;
  std::vector<float> v(n);
  h5::check(H5Dread(ds.get(), H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()), "read " + name);
  return v;
}

bool binary(const std::vector<float>& v) {
  for (float x : v)
    if (x != 0.f && x != 1.f) return false;
  return true;
}

}  // namespace

TEST_CASE("bench train: JSON rows per stage and the kept batches' shapes (micro, no torch)", "[bench][cli]") {
  yelan::test::CliTempDir d("bench-train");
  const auto r = run_cli({"bench", "train", "--config", "micro", "--batch", "2", "--batches", "3", "--steps", "2", "--sim",
                          kScenes, "--no-torch", "--json", "--keep-data", d / "b.h5"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto js = nlohmann::json::parse(r.out);
  REQUIRE(js.is_array());
  REQUIRE(js.size() == 2);  // --stage both, --threads-list 1
  CHECK(js[0]["stage"] == "pose");
  CHECK(js[1]["stage"] == "mask");
  for (const auto& row : js) {
    for (const char* key : {"config", "stage", "threads", "batch", "frames_per_step", "ours_ms_per_step", "ours_samples_per_s",
                            "torch_ms_per_step", "torch_samples_per_s", "ratio", "initial_loss", "torch_initial_loss"})
      CHECK(row.contains(key));
    CHECK(row["config"] == "micro");
    CHECK(row["threads"] == 1);
    CHECK(row["batch"] == 2);
    CHECK(row["frames_per_step"] == 4);  // 2 windows x 2 frames
    // samples/s is frames per step over the median step time (consistency, not speed)
    const double ms = row["ours_ms_per_step"], sps = row["ours_samples_per_s"];
    CHECK(ms > 0);
    CHECK(sps * ms / 1e3 == Approx(4.0).epsilon(1e-6));
    CHECK(row["torch_samples_per_s"].is_null());
    CHECK(row["ratio"].is_null());
    const double loss = row["initial_loss"];
    CHECK(std::isfinite(loss));
    CHECK(loss > 0);
  }

  h5::silence_errors();
  h5::H5Id f = h5::open_file(d / "b.h5");
  CHECK(h5::read_attr_string(f.get(), "format") == "yelan-train-bench");
  std::vector<hsize_t> dims;
  const auto pose_in = read(f.get(), "pose/input", dims);
  CHECK(dims == std::vector<hsize_t>{3, 4, 6, 32, 43});  // batches, frames, TORE planes, 260/8, 346/8
  read(f.get(), "pose/target", dims);
  CHECK(dims == std::vector<hsize_t>{3, 4, 13, 3});
  CHECK(binary(read(f.get(), "pose/valid", dims)));
  CHECK(dims == std::vector<hsize_t>{3, 4, 13});
  const auto mask_in = read(f.get(), "mask/input", dims);
  CHECK(dims == std::vector<hsize_t>{3, 4, 6, 32, 43});
  const auto labels = read(f.get(), "mask/labels", dims);
  CHECK(dims == std::vector<hsize_t>{3, 4, 3, 32, 43});  // n_masks 3
  CHECK(binary(labels));
  // Real simulated data: events in every batch, and the pose input is masked (zero cells).
  const std::size_t per_batch = pose_in.size() / 3;
  for (int b = 0; b < 3; ++b) {
    double sum = 0;
    int zeros = 0;
    for (std::size_t i = b * per_batch; i < (b + 1) * per_batch; ++i) sum += pose_in[i], zeros += pose_in[i] == 0.f;
    CHECK(sum > 0);
    CHECK(zeros > 0);
  }
  // Labels are the current and future masks: channel 1 of frame t is channel 0 of frame t+1
  // (frames 0 and 1 of each window; each window is 2 frames of micro).
  const std::size_t plane = 32 * 43;
  for (std::size_t win = 0; win < 3 * 2; ++win) {
    const float* t0 = labels.data() + (win * 2 + 0) * 3 * plane;
    const float* t1 = labels.data() + (win * 2 + 1) * 3 * plane;
    CHECK(std::equal(t0 + plane, t0 + 2 * plane, t1));
  }
  // The initial weights beside the data are a valid weights file of the config.
  const auto v = run_cli({"weights", "verify", d / "b.weights.h5", "--config", "micro"});
  INFO(v.err);
  CHECK(v.code == 0);
}

TEST_CASE("bench train: bad usage exits 2", "[bench][cli]") {
  CHECK(run_cli({"bench", "train", "--stage", "legs", "--no-torch"}).code == 2);
  CHECK(run_cli({"bench", "train", "--config", "no-such-config", "--no-torch"}).code == 2);
  CHECK(run_cli({"bench", "train", "--config", "micro", "--steps", "0", "--no-torch"}).code == 2);
  CHECK(run_cli({"bench", "train", "--config", "micro", "--threads-list", "0", "--no-torch"}).code == 2);
  CHECK(run_cli({"bench", "train", "--config", "micro", "--sim", "nowhere-at-all", "--no-torch"}).code == 2);
}

// Same config, same batches, same initial weights: the first step's loss (before any update)
// must agree with PyTorch's, or the two would not be training the same thing.
TEST_CASE("bench train: PyTorch's initial loss equals ours on the same batches", "[bench][torch]") {
  if (std::system("/usr/bin/python3 -c 'import torch, h5py' >/dev/null 2>&1") != 0) {
    std::printf("SKIP: PyTorch comparison NOT checked: /usr/bin/python3 cannot import torch and h5py\n");
    std::fflush(stdout);
    std::exit(77);
  }
  const auto r = run_cli({"bench", "train", "--config", "micro", "--batch", "2", "--batches", "2", "--steps", "1", "--sim",
                          kScenes, "--json"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  const auto js = nlohmann::json::parse(r.out);
  REQUIRE(js.size() == 2);
  for (const auto& row : js) {
    INFO(row.dump());
    REQUIRE(row["torch_initial_loss"].is_number());
    const double ours = row["initial_loss"], theirs = row["torch_initial_loss"];
    CHECK(std::abs(ours - theirs) <= 1e-3 * std::abs(theirs));
    CHECK(row["ratio"].is_number());
  }
  CHECK_FALSE(yelan::test::contains(r.err, "warning"));
}

TEST_CASE("bench: chart labels of points that coincide stack instead of overlapping", "[bench]") {
  yelan::test::CliTempDir d("xy-chart");
  // Three betas giving the same time and accuracy (stage 1 on every tick), one elsewhere.
  yelan::bench::XySeries s{"paper protocol", "#2471a3", {{10, 300, "beta 0.95"}, {10, 300, "beta 0.99"}, {10, 300, "beta 1.01"},
                                                         {3, 310, "beta 0.5"}}};
  yelan::bench::write_xy_chart(d / "c.svg", "t", "x", "y", {s});
  const std::string svg = yelan::test::slurp(d / "c.svg");
  auto label_y = [&](const std::string& label) {
    const std::size_t end = svg.find(">" + label + "</text>");
    REQUIRE(end != std::string::npos);
    const std::size_t y = svg.rfind("y=\"", end);
    return std::stod(svg.substr(y + 3));
  };
  const double a = label_y("beta 0.95"), b = label_y("beta 0.99"), c = label_y("beta 1.01");
  CHECK(std::abs(a - b) >= 13);
  CHECK(std::abs(b - c) >= 13);
  CHECK(std::abs(a - c) >= 13);
}

TEST_CASE("bench: charts are written through temporary files of their own, never through a planted link", "[bench]") {
  yelan::test::CliTempDir d("xy-chart-links");
  std::ofstream(d / "precious") << "precious";
  for (const char* planted : {"c.svg.tmp", "c.png.tmp"})  // the names the writer used to use
    std::filesystem::create_symlink(d / "precious", d / planted);
  const yelan::bench::XySeries s{"a", "#2471a3", {{1, 2, "one"}, {3, 4, "two"}}};
  const std::string png = yelan::bench::write_xy_chart(d / "c.svg", "t", "x", "y", {s});
  CHECK(yelan::test::slurp(d / "precious") == "precious");
  CHECK(yelan::test::contains(yelan::test::slurp(d / "c.svg"), "</svg>"));
  if (!png.empty()) CHECK(yelan::test::slurp(png).substr(1, 3) == "PNG");
  for (const auto& e : std::filesystem::directory_iterator(d.p)) CHECK(e.path().string().find(".tmp-") == std::string::npos);
}
