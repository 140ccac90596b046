// Writes the seed corpora for the fuzz targets: slices of the real recordings (when
// ../shared/data/events is there), small files from our writers, and synthetic EVT 2.1.
// usage: make_seeds SHARED_EVENTS_DIR OUT_DIR
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <hdf5.h>

#include "camera/io/event_writer.h"
#include "camera/io/flatbuf.h"
#include "camera/io/h5.h"
#include "weights_tools/weights_file.h"

namespace fs = std::filesystem;
using Bytes = std::vector<unsigned char>;

namespace {

Bytes slurp(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

void dump(const fs::path& p, const Bytes& b) {
  fs::create_directories(p.parent_path());
  std::ofstream f(p, std::ios::binary);
  f.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
}

std::size_t raw_data_offset(const Bytes& b) {
  std::size_t at = 0;
  while (at < b.size() && b[at] == '%') {
    while (at < b.size() && b[at] != '\n') ++at;
    ++at;
  }
  return at;
}

// Slices of the words after the header, each `len` bytes, aligned to `word`.
void raw_slices(const Bytes& b, std::size_t word, const fs::path& dir, const std::string& name) {
  const std::size_t start = raw_data_offset(b), len = 4096 / word * word;
  for (int k = 0; k < 8 && start + len <= b.size(); ++k) {
    const std::size_t at = start + (b.size() - start - len) / 8 * static_cast<std::size_t>(k) / word * word;
    dump(dir / (name + "_" + std::to_string(k)), Bytes(b.begin() + static_cast<long>(at), b.begin() + static_cast<long>(at + len)));
  }
}

// The real AEDAT 4.0 header plus its first event packet and one packet of each other stream.
Bytes aedat4_excerpt(const Bytes& b) {
  std::uint32_t hdr = 0;
  std::memcpy(&hdr, b.data() + 14, 4);
  std::size_t at = 18 + hdr;
  Bytes out(b.begin(), b.begin() + static_cast<long>(at));
  bool seen[4] = {};
  while (at + 8 <= b.size()) {
    std::int32_t stream = 0, size = 0;
    std::memcpy(&stream, b.data() + at, 4);
    std::memcpy(&size, b.data() + at + 4, 4);
    if (size <= 0 || at + 8 + static_cast<std::size_t>(size) > b.size() || stream < 0 || stream > 3) break;
    if (!seen[stream]) {
      seen[stream] = true;
      out.insert(out.end(), b.begin() + static_cast<long>(at), b.begin() + static_cast<long>(at + 8 + static_cast<std::size_t>(size)));
    }
    at += 8 + static_cast<std::size_t>(size);
  }
  // The excerpt has no data table: set the header's dataTablePosition to -1 (none).
  auto table = yelan::camera::flat::root(out.data() + 18, hdr);
  if (auto field = yelan::camera::flat::field(table, 1, 8)) {
    const std::int64_t none = -1;
    std::memcpy(out.data() + 18 + *field, &none, 8);
  }
  return out;
}

void write_events(const std::string& path, int n, int w, int h) {
  auto wr = yelan::camera::open_event_writer(path, {"", w, h, {}, {}});
  std::vector<yelan::camera::Event> ev;
  for (int i = 0; i < n; ++i)
    ev.push_back({1000 + i * 3, static_cast<std::uint16_t>((i * 7) % w), static_cast<std::uint16_t>((i * 5) % h),
                  static_cast<std::uint8_t>(i & 1)});
  wr->write(ev);
  wr->close();
}

// A labelled recording as `yelan sim` lays it out, on a 16 x 12 sensor so it stays small:
// events, /camera (width, height, K), /labels (t, joints, valid), /masks (t, data).
void write_recording(const std::string& path) {
  namespace h5 = yelan::camera::h5;
  constexpr int W = 16, H = 12, L = 12, M = 3;
  auto wr = yelan::camera::open_yelan_h5_writer(path, {"", W, H, {}, {}});
  std::vector<yelan::camera::Event> ev;
  for (int i = 0; i < 200; ++i)
    ev.push_back({i * 300, std::uint16_t(i * 7 % W), std::uint16_t(i * 5 % H), std::uint8_t(i & 1)});
  wr->write(ev);
  const hid_t f = hid_t(yelan::camera::yelan_h5_file(*wr));
  const auto put_ds = [&](const char* name, hid_t ftype, hid_t mtype, std::vector<hsize_t> dims, const void* data) {
    h5::H5Id space = h5::check(H5Screate_simple(int(dims.size()), dims.data(), nullptr), name);
    h5::H5Id ds = h5::check(H5Dcreate2(f, name, ftype, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), name);
    h5::check(H5Dwrite(ds.get(), mtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), name);
  };
  const auto put_scalar = [&](const char* name, std::int64_t v) {
    h5::H5Id space = h5::check(H5Screate(H5S_SCALAR), name);
    h5::H5Id ds = h5::check(H5Dcreate2(f, name, H5T_STD_I64LE, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), name);
    h5::check(H5Dwrite(ds.get(), H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, &v), name);
  };
  h5::create_group(f, "camera");
  h5::create_group(f, "labels");
  h5::create_group(f, "masks");
  put_scalar("camera/width", W);
  put_scalar("camera/height", H);
  const double k[9] = {20, 0, 8, 0, 20, 6, 0, 0, 1};
  put_ds("camera/K", H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE, {3, 3}, k);
  std::vector<std::int64_t> lt(L), mt(M);
  std::vector<float> joints(L * 13 * 3);
  std::vector<std::uint8_t> valid(L * 13, 1), masks(std::size_t(M) * W * H);
  for (int i = 0; i < L; ++i) lt[std::size_t(i)] = i * 5000;
  for (int i = 0; i < M; ++i) mt[std::size_t(i)] = i * 20000;
  for (std::size_t i = 0; i < joints.size(); ++i) joints[i] = float(i % 97) * 10 + 3000 * float(i % 3 == 2);
  for (std::size_t i = 0; i < masks.size(); ++i) masks[i] = (i / 5) % 2;
  put_ds("labels/t", H5T_STD_I64LE, H5T_NATIVE_INT64, {L}, lt.data());
  put_ds("labels/joints", H5T_IEEE_F32LE, H5T_NATIVE_FLOAT, {L, 13, 3}, joints.data());
  put_ds("labels/valid", H5T_STD_U8LE, H5T_NATIVE_UINT8, {L, 13}, valid.data());
  put_ds("masks/t", H5T_STD_I64LE, H5T_NATIVE_INT64, {M}, mt.data());
  put_ds("masks/data", H5T_STD_U8LE, H5T_NATIVE_UINT8, {M, H, W}, masks.data());
  h5::write_attr_string(f, "character", "ana");
  h5::write_attr_string(f, "scene", "{\"occluders\": false}");
  h5::write_attr_i64(f, "dancer", 1);
  wr->close();
}

// A weights file with a few small tensors in each group and a config (its structure, not a
// network: load_weights does not check the config's shapes).
void write_weights(const std::string& path) {
  yelan::weights::Weights w;
  w.config_json = R"({"name": "seed", "input": {}, "mask": {}, "pose": {}})";
  w.groups["mask"]["inc.double_conv.0.weight"] = {{2, 3, 3, 3}, std::vector<float>(54, 0.25f)};
  w.groups["mask"]["inc.double_conv.1.running_mean"] = {{2}, {0.5f, -0.5f}};
  w.groups["pose"]["fc.bias"] = {{3}, {1, 2, 3}};
  yelan::weights::save_weights(path, w);
}

template <typename T>
void put(Bytes& b, T v) {
  for (std::size_t i = 0; i < sizeof(T); ++i) b.push_back(static_cast<unsigned char>(static_cast<std::uint64_t>(v) >> (8 * i)));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: make_seeds SHARED_EVENTS_DIR OUT_DIR\n");
    return 2;
  }
  const fs::path shared = argv[1], out = argv[2];
  if (fs::exists(shared / "evt2_sample.raw")) {
    const Bytes e2 = slurp(shared / "evt2_sample.raw");
    raw_slices(e2, 4, out / "evt2", "real");
    dump(out / "raw_header" / "evt2_head", Bytes(e2.begin(), e2.begin() + 4096));
  }
  if (fs::exists(shared / "evt3_sample.raw")) {
    const Bytes e3 = slurp(shared / "evt3_sample.raw");
    raw_slices(e3, 2, out / "evt3", "real");
    dump(out / "raw_header" / "evt3_head", Bytes(e3.begin(), e3.begin() + 4096));
  }
  if (fs::exists(shared / "aestream_davis.aedat4"))
    dump(out / "aedat4" / "real_excerpt", aedat4_excerpt(slurp(shared / "aestream_davis.aedat4")));

  // EVT 2.1: time-high words and vector words, ON and OFF.
  Bytes e21;
  for (int k = 0; k < 64; ++k) {
    const std::uint64_t t = 4096 + static_cast<std::uint64_t>(k) * 40;
    if (k % 8 == 0) put<std::uint64_t>(e21, (std::uint64_t{8} << 60) | ((t >> 6) << 32));
    put<std::uint64_t>(e21, (std::uint64_t(k & 1) << 60) | ((t & 63) << 54) | (std::uint64_t(32 * (k % 40)) << 43) |
                                (std::uint64_t(k * 11 % 720) << 32) | (0x9000'0F01u ^ static_cast<std::uint32_t>(k)));
  }
  dump(out / "evt21" / "synthetic", e21);
  dump(out / "raw_header" / "evt21", [&] {
    const std::string h = "% format EVT21;height=720;width=1280\n% end\n";
    Bytes b(h.begin(), h.end());
    b.insert(b.end(), e21.begin(), e21.end());
    return b;
  }());

  fs::create_directories(out / "aedat4");
  fs::create_directories(out / "text");
  fs::create_directories(out / "hdf5");
  write_events((out / "aedat4" / "ours_10.aedat4").string(), 10, 346, 260);
  write_events((out / "aedat4" / "ours_300.aedat4").string(), 300, 64, 48);
  write_events((out / "text" / "ours_20.txt").string(), 20, 346, 260);
  write_events((out / "hdf5" / "ours_50.yelan.h5").string(), 50, 346, 260);
  fs::create_directories(out / "recording");
  fs::create_directories(out / "weights");
  write_recording((out / "recording" / "tiny.yelan.h5").string());
  write_weights((out / "weights" / "tiny.h5").string());
  // AEDAT 2.0 (DAVIS layout, big-endian) and 3.1 (one polarity packet).
  {
    const std::string h2 = "#!AER-DAT2.0\r\n# HardwareInterface: DAVIS346\r\n";
    Bytes a2(h2.begin(), h2.end());
    for (std::uint32_t i = 0; i < 32; ++i) {
      const std::uint32_t addr = ((i * 7 % 260) << 22) | ((i * 11 % 346) << 12) | ((i & 1) << 11) | (i & 3);
      const std::uint32_t ts = 1000 + 5 * i;
      for (int k = 3; k >= 0; --k) a2.push_back(static_cast<unsigned char>(addr >> (8 * k)));
      for (int k = 3; k >= 0; --k) a2.push_back(static_cast<unsigned char>(ts >> (8 * k)));
    }
    dump(out / "aedat_legacy" / "aedat2", a2);
    const std::string h3 = "#!AER-DAT3.1\r\n#Source 1: DAVIS346\r\n#!END-HEADER\r\n";
    Bytes a3(h3.begin(), h3.end());
    for (std::int32_t v : {0x00010001, 8, 0, 0, 4, 4, 4}) put<std::int32_t>(a3, v);  // type 1, source 1
    for (std::uint32_t i = 0; i < 4; ++i) {
      put<std::uint32_t>(a3, ((i * 50) << 17) | ((i * 30) << 2) | ((i & 1) << 1) | 1u);
      put<std::int32_t>(a3, static_cast<std::int32_t>(100 + i));
    }
    dump(out / "aedat_legacy" / "aedat3", a3);
  }
  // .npy: t i8, x i2, y i2, p u1 (expelliarmus' layout), 8 records.
  {
    std::string dict = "{'descr': [('t', '<i8'), ('x', '<i2'), ('y', '<i2'), ('p', '|u1')], "
                       "'fortran_order': False, 'shape': (8,), }";
    while ((10 + dict.size() + 1) % 64) dict += ' ';
    dict += '\n';
    Bytes n = {0x93, 'N', 'U', 'M', 'P', 'Y', 1, 0};
    put<std::uint16_t>(n, static_cast<std::uint16_t>(dict.size()));
    n.insert(n.end(), dict.begin(), dict.end());
    for (int i = 0; i < 8; ++i) {
      put<std::int64_t>(n, 11718656 + i);
      put<std::int16_t>(n, static_cast<std::int16_t>(i * 100));
      put<std::int16_t>(n, static_cast<std::int16_t>(i * 50));
      n.push_back(static_cast<unsigned char>(i & 1));
    }
    dump(out / "npy" / "expelliarmus_like", n);
  }
  const std::string rpg = "240 180\n0.000001 1 2 1\n1.5,3,4,-1\n12.3456785 5 6 0\n1e-3 7 8 1\n";
  dump(out / "text" / "rpg", Bytes(rpg.begin(), rpg.end()));
  return 0;
}
