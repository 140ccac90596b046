// Helpers for the camera/io tests: scratch files, reading whole (small) streams, and
// encoders that build Prophesee RAW byte streams word by word (for formats with no sample).
#pragma once
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "camera/io/event_reader.h"
#include "camera/io/h5.h"

namespace yelan::test {

// A per-test scratch directory, removed at the end of the test.
struct ScratchDir {
  std::filesystem::path dir;
  explicit ScratchDir(const std::string& name)
      : dir(std::filesystem::temp_directory_path() / ("yelan_io_" + name + "_" + std::to_string(::getpid()))) {
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
  }
  std::string file(const std::string& name) const { return (dir / name).string(); }
};

inline std::vector<unsigned char> read_bytes(const std::string& path) {
  std::ifstream f(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

inline void write_bytes(const std::string& path, const std::vector<unsigned char>& b) {
  std::ofstream f(path, std::ios::binary);
  f.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
}

inline void write_text(const std::string& path, const std::string& s) {
  std::ofstream f(path, std::ios::binary);
  f << s;
}

inline std::vector<camera::Event> read_all(camera::EventReader& r, std::size_t batch = 4096) {
  std::vector<camera::Event> out;
  while (r.read(out, batch) > 0) {
  }
  return out;
}

inline std::vector<camera::Event> read_all(const std::string& path) {
  auto r = camera::open_event_file(path);
  return read_all(*r);
}

// A 1-D HDF5 dataset holding `v` (file layouts of other tools, built with the C API).
template <typename T>
void h5_dataset_1d(hid_t loc, const char* name, hid_t file_type, hid_t mem_type, const std::vector<T>& v) {
  namespace h5 = camera::h5;
  hsize_t n[1] = {v.size()};
  h5::H5Id space = h5::check(H5Screate_simple(1, n, nullptr), "space");
  h5::H5Id ds = h5::check(H5Dcreate2(loc, name, file_type, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), name);
  h5::check(H5Dwrite(ds.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data()), name);
}

// Little-endian word writers for RAW payloads.
template <typename T>
void put_le(std::vector<unsigned char>& b, T v) {
  for (std::size_t i = 0; i < sizeof(T); ++i) b.push_back(static_cast<unsigned char>(static_cast<std::uint64_t>(v) >> (8 * i)));
}

inline std::vector<unsigned char> raw_header(const std::string& lines) {
  return std::vector<unsigned char>(lines.begin(), lines.end());
}

// EVT 2.1 words.
inline std::uint64_t evt21_time_high(std::int64_t t) {
  return (std::uint64_t{0x8} << 60) | ((static_cast<std::uint64_t>(t >> 6) & 0x0FFFFFFF) << 32);
}
inline std::uint64_t evt21_cd(std::int64_t t, unsigned x_base, unsigned y, unsigned p, std::uint32_t mask) {
  return (std::uint64_t{p & 1u} << 60) | ((static_cast<std::uint64_t>(t) & 0x3F) << 54) |
         (std::uint64_t{x_base & 0x7FFu} << 43) | (std::uint64_t{y & 0x7FFu} << 32) | mask;
}
// EVT 2.0 words.
inline std::uint32_t evt2_time_high(std::int64_t t) {
  return (0x8u << 28) | (static_cast<std::uint32_t>(t >> 6) & 0x0FFFFFFFu);
}
inline std::uint32_t evt2_cd(std::int64_t t, unsigned x, unsigned y, unsigned p) {
  return ((p & 1u) << 28) | ((static_cast<std::uint32_t>(t) & 0x3Fu) << 22) | ((x & 0x7FFu) << 11) | (y & 0x7FFu);
}
// EVT 3.0 words.
inline std::uint16_t evt3(unsigned type, unsigned payload) {
  return static_cast<std::uint16_t>((type << 12) | (payload & 0xFFFu));
}

}  // namespace yelan::test
