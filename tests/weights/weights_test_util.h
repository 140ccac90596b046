// Helpers of the weights tests: a scratch directory, the CLI in-process, and raw HDF5
// writing for files our writer would never produce (foreign, damaged, mis-typed).
#pragma once
#include <hdf5.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <vector>

#include "engine/cli/cli.h"
#include "weights_tools/weights_file.h"
#include "cli_util.h"

namespace yelan::test {

namespace fs = std::filesystem;

struct TempDir {
  fs::path path;
  explicit TempDir(const std::string& name)
      : path(fs::temp_directory_path() / ("yelan_weights_" + name + "_" + std::to_string(::getpid()))) {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  std::string operator/(const std::string& f) const { return (path / f).string(); }
  // Names of everything in the directory (to see that no temp file was left).
  std::vector<std::string> listing() const {
    std::vector<std::string> out;
    for (const auto& e : fs::directory_iterator(path)) out.push_back(e.path().filename().string());
    return out;
  }
};

using yelan::test::CliResult;
inline CliResult yelan_cli(std::vector<std::string> argv) { return yelan::test::run_cli(std::move(argv)); }
inline bool has(const std::string& s, const std::string& what) { return yelan::test::contains(s, what); }

inline std::string fixture(const std::string& name) {
  return (fs::path(__FILE__).parent_path() / "data" / name).string();
}

// A small valid weights object: odd sizes, a scalar, an empty mask group allowed.
inline weights::Weights sample_weights() {
  weights::Weights w;
  w.config_json = R"({"name":"sample","pose":{"stages":1}})";
  auto& pose = w.groups["pose"];
  pose["in_cnn.0.weight"] = {{3, 2, 1, 5}, {}};
  for (int i = 0; i < 30; ++i) pose["in_cnn.0.weight"].data.push_back(0.25f * static_cast<float>(i) - 3.f);
  pose["in_cnn.1.num_batches_tracked"] = {{}, {1234.f}};
  pose["in_cnn.1.running_var"] = {{3}, {1.f, 2.f, 0.5f}};
  w.groups["mask"]["fc.bias"] = {{7}, {1, -1, 2, -2, 3, -3, 1e-30f}};
  return w;
}

// Raw HDF5 files: the header attributes and datasets a test wants, nothing checked.
class RawH5 {
 public:
  explicit RawH5(const std::string& path) {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    file_ = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  }
  ~RawH5() {
    for (auto it = groups_.rbegin(); it != groups_.rend(); ++it) H5Gclose(*it);
    if (file_ >= 0) H5Fclose(file_);
  }
  hid_t root() const { return file_; }
  void str_attr(const std::string& name, const std::string& value) {
    hid_t t = H5Tcopy(H5T_C_S1);
    H5Tset_size(t, value.size() + 1);  // fixed-length this time: the reader takes both
    hid_t s = H5Screate(H5S_SCALAR);
    hid_t a = H5Acreate2(file_, name.c_str(), t, s, H5P_DEFAULT, H5P_DEFAULT);
    H5Awrite(a, t, value.c_str());
    H5Aclose(a);
    H5Sclose(s);
    H5Tclose(t);
  }
  void int_attr(const std::string& name, long long v) {
    hid_t s = H5Screate(H5S_SCALAR);
    hid_t a = H5Acreate2(file_, name.c_str(), H5T_STD_I64LE, s, H5P_DEFAULT, H5P_DEFAULT);
    H5Awrite(a, H5T_NATIVE_LLONG, &v);
    H5Aclose(a);
    H5Sclose(s);
  }
  // The header of a valid weights file.
  void header(const std::string& format = "yelan-weights", long long version = 1,
              const std::string& config = R"({"name":"raw"})") {
    str_attr("format", format);
    int_attr("version", version);
    str_attr("config", config);
  }
  hid_t group(const std::string& name) {
    hid_t g = H5Gcreate2(file_, name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    groups_.push_back(g);
    return g;
  }
  // A dataset of `file_type`, written from doubles when `write` (otherwise never stored).
  void dataset(hid_t loc, const std::string& name, hid_t file_type, std::vector<hsize_t> dims,
               bool write = true, bool chunked = false) {
    hid_t s = dims.empty() ? H5Screate(H5S_SCALAR) : H5Screate_simple(static_cast<int>(dims.size()), dims.data(), nullptr);
    hid_t p = H5Pcreate(H5P_DATASET_CREATE);
    if (chunked) {
      std::vector<hsize_t> chunk(dims.size(), 1);
      H5Pset_chunk(p, static_cast<int>(chunk.size()), chunk.data());
    }
    hid_t d = H5Dcreate2(loc, name.c_str(), file_type, s, H5P_DEFAULT, p, H5P_DEFAULT);
    if (write) {
      hsize_t n = 1;
      for (auto x : dims) n *= x;
      std::vector<double> v(n, 0.5);
      H5Dwrite(d, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
    }
    H5Dclose(d);
    H5Pclose(p);
    H5Sclose(s);
  }

 private:
  hid_t file_ = -1;
  std::vector<hid_t> groups_;
};

}  // namespace yelan::test
