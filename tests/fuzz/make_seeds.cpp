// Writes the seed corpora for the fuzz targets: slices of the real recordings (when
// ../shared/data/events is there), small files from our writers, and synthetic EVT 2.1.
// usage: make_seeds SHARED_EVENTS_DIR OUT_DIR
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "camera/io/event_writer.h"
#include "camera/io/flatbuf.h"

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
  const std::string rpg = "240 180\n0.000001 1 2 1\n1.5,3,4,-1\n12.3456785 5 6 0\n1e-3 7 8 1\n";
  dump(out / "text" / "rpg", Bytes(rpg.begin(), rpg.end()));
  return 0;
}
