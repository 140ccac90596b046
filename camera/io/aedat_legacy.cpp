#include "camera/io/aedat_legacy.h"

#include <array>
#include <cstring>

#include "camera/io/byte_source_reader.h"

namespace yelan::camera {
namespace {

constexpr std::size_t kMaxHeader = 1 << 20;
constexpr std::uint64_t kMaxPacketBytes = 256u << 20;

std::uint32_t load_be32(const unsigned char* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | p[3];
}

void size_from_header(const std::string& header, StreamInfo& info) {
  if (header.find("DAVIS346") != std::string::npos) info.width = 346, info.height = 260;
  else if (header.find("DAVIS240") != std::string::npos) info.width = 240, info.height = 180;
  else if (header.find("DVXplorer") != std::string::npos || header.find("DVXPLORER") != std::string::npos)
    info.width = 640, info.height = 480;
}

class AedatLegacyReader final : public ByteSourceReader {
 public:
  AedatLegacyReader(const std::string& path, int camera) : ByteSourceReader(path), camera_(camera) {
    read_header();
    restart();
  }

 protected:
  void restart() override {
    src_.seek(data_offset_);
    have_time_ = false;
    epoch_ = 0;
    last_ts_ = 0;
  }

  bool decode(std::vector<Event>& out) override { return version_ == 2 ? decode_v2(out) : decode_v31(out); }

 private:
  void read_header() {
    std::string header, line;
    unsigned char c = 0;
    while (true) {
      if (src_.read_some(&c, 1) != 1) break;
      if (c != '#') {
        src_.seek(src_.offset() - 1);
        break;
      }
      line = "#";
      while (src_.read_some(&c, 1) == 1 && c != '\n') {
        line.push_back(static_cast<char>(c));
        if (header.size() + line.size() > kMaxHeader) src_.fail("AEDAT header longer than 1 MiB");
      }
      header += line + "\n";
      if (line.rfind("#!END-HEADER", 0) == 0) break;
    }
    data_offset_ = src_.offset();
    if (header.rfind("#!AER-DAT2.0", 0) == 0) {
      version_ = 2;
      info_.format = "aedat2";
    } else if (header.rfind("#!AER-DAT3.1", 0) == 0) {
      version_ = 31;
      info_.format = "aedat3";
      if (header.find("#!END-HEADER") == std::string::npos) src_.fail("AEDAT 3.1 header has no #!END-HEADER line");
    } else {
      src_.fail_at(0, "not an AEDAT 2.0 or 3.1 file (bad magic)");
    }
    size_from_header(header, info_);
  }

  // Extends 32-bit timestamps: a drop of more than half the range is a counter wrap.
  std::int64_t unwrap32(std::uint32_t ts) {
    const std::int64_t range = std::int64_t{1} << 32;
    std::int64_t t = static_cast<std::int64_t>(ts) + epoch_;
    if (have_time_ && t < last_ts_ - range / 2) {
      epoch_ += range;
      t += range;
    }
    have_time_ = true;
    last_ts_ = t;
    return t;
  }

  bool decode_v2(std::vector<Event>& out) {
    const std::size_t got = src_.read_some(block_.data(), block_.size());
    const std::size_t whole = got - got % 8;
    const std::uint64_t at = src_.offset() - got;
    if (whole < got)
      warn_skipped(at + whole, "file ends inside an 8-byte event (" + std::to_string(got - whole) + " bytes ignored)");
    for (std::size_t i = 0; i < whole; i += 8) {
      const std::uint32_t addr = load_be32(block_.data() + i);
      const std::uint32_t ts = load_be32(block_.data() + i + 4);
      if ((addr >> 31) || (addr & 0x400u)) continue;  // APS, IMU or special events
      if (camera_ >= 0 && static_cast<int>(addr & 0xFu) != camera_) continue;
      out.push_back({unwrap32(ts), static_cast<std::uint16_t>((addr >> 12) & 0x3FF),
                     static_cast<std::uint16_t>((addr >> 22) & 0x1FF), static_cast<std::uint8_t>((addr >> 11) & 1)});
    }
    return got == block_.size();
  }

  bool decode_v31(std::vector<Event>& out) {
    const std::uint64_t at = src_.offset();
    if (at == src_.size()) return false;
    unsigned char h[28];
    src_.read_exact(h, 28, "AEDAT 3.1 packet header");
    const std::int16_t type = load_le<std::int16_t>(h);
    const std::int32_t size = load_le<std::int32_t>(h + 4), overflow = load_le<std::int32_t>(h + 12);
    const std::int32_t capacity = load_le<std::int32_t>(h + 16), number = load_le<std::int32_t>(h + 20);
    if (size <= 0 || capacity < 0 || number < 0 || number > capacity || overflow < 0 ||
        static_cast<std::uint64_t>(size) * static_cast<std::uint64_t>(capacity) > kMaxPacketBytes)
      src_.fail_at(at, "absurd packet header (event size " + std::to_string(size) + ", capacity " +
                           std::to_string(capacity) + ", number " + std::to_string(number) + ")");
    const std::uint64_t bytes = static_cast<std::uint64_t>(size) * static_cast<std::uint64_t>(capacity);
    if (bytes > src_.remaining())
      src_.fail_at(at, "truncated packet: needs " + std::to_string(bytes) + " bytes, " +
                           std::to_string(src_.remaining()) + " remain");
    if (type != 1) {  // not polarity events
      src_.seek(src_.offset() + bytes);
      return true;
    }
    if (size != 8) src_.fail_at(at + 4, "polarity events must be 8 bytes, header says " + std::to_string(size));
    packet_.resize(static_cast<std::size_t>(bytes));
    src_.read_exact(packet_.data(), packet_.size(), "AEDAT 3.1 packet");
    const std::int64_t high = static_cast<std::int64_t>(overflow) << 31;
    for (std::int32_t i = 0; i < number; ++i) {
      const unsigned char* e = packet_.data() + 8 * static_cast<std::size_t>(i);
      const std::uint32_t data = load_le<std::uint32_t>(e);
      const std::int32_t ts = load_le<std::int32_t>(e + 4);
      if (!(data & 1u)) continue;  // invalidated event
      out.push_back({high | (ts & 0x7FFFFFFF), static_cast<std::uint16_t>((data >> 17) & 0x7FFF),
                     static_cast<std::uint16_t>((data >> 2) & 0x7FFF), static_cast<std::uint8_t>((data >> 1) & 1)});
    }
    return true;
  }

  int camera_;
  int version_ = 0;
  std::uint64_t data_offset_ = 0;
  std::array<unsigned char, 1 << 16> block_{};
  std::vector<unsigned char> packet_;
  bool have_time_ = false;
  std::int64_t epoch_ = 0, last_ts_ = 0;
};

}  // namespace

std::unique_ptr<EventReader> open_aedat_legacy(const std::string& path, int camera) {
  return std::make_unique<AedatLegacyReader>(path, camera);
}

}  // namespace yelan::camera
