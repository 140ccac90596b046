#include <algorithm>
#include <charconv>
#include <climits>
#include <cstring>

#include "camera/io/aedat4.h"
#include "camera/io/byte_source_reader.h"
#include "camera/io/compression.h"
#include "camera/io/flatbuf.h"

namespace yelan::camera {
namespace {

constexpr std::size_t kMaxHeaderBytes = 16 << 20;
constexpr std::size_t kMaxPacketBytes = 256 << 20;        // compressed, as stored
constexpr std::size_t kMaxDecompressedBytes = 512 << 20;  // 32 M events
constexpr std::size_t kEventBytes = 16;                   // struct {int64 t; int16 x, y; bool on;}

std::string attr_value(const std::string& xml, std::size_t open_end, std::size_t& next) {
  std::size_t close = xml.find("</attr>", open_end);
  if (close == std::string::npos) {
    next = xml.size();
    return {};
  }
  next = close + 7;
  return xml.substr(open_end, close - open_end);
}

int to_int(const std::string& s) {
  int v = 0;
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  return ec == std::errc() && v > 0 && v <= 65536 ? v : 0;
}

class Aedat4Reader final : public ByteSourceReader {
 public:
  explicit Aedat4Reader(const std::string& path) : ByteSourceReader(path) {
    info_.format = "aedat4";
    read_header();
  }
  bool fast_seek() const override { return data_table_ >= 0; }

 protected:
  void restart() override { src_.seek(first_packet_); }

  // Jumps to the first event packet that ends at or after t, using the file's data table
  // (FileDataTable: byte offset, stream, timestamps per packet). A missing or unreadable
  // table only costs speed: the caller then decodes from the start.
  bool seek_index(std::int64_t t) override {
    if (!table_loaded_) load_table();
    if (table_.empty()) return false;
    for (const auto& [offset, t_end] : table_)
      if (t_end >= t) {
        src_.seek(offset - 8);
        return true;
      }
    src_.seek(static_cast<std::uint64_t>(data_table_));
    return true;
  }

  bool decode(std::vector<Event>& out) override {
    const std::uint64_t at = src_.offset();
    const std::uint64_t end = data_table_ >= 0 ? static_cast<std::uint64_t>(data_table_) : src_.size();
    if (at >= end) return false;
    if (at == src_.size())
      src_.fail("file ends before its data table at offset " + std::to_string(data_table_) + " (truncated?)");
    unsigned char head[8];
    src_.read_exact(head, 8, "packet header");
    const std::int32_t stream = load_le<std::int32_t>(head);
    const std::int32_t size = load_le<std::int32_t>(head + 4);
    auto it = streams_.find(stream);
    if (it == streams_.end())
      src_.fail_at(at, "packet names stream " + std::to_string(stream) + ", which the header does not declare");
    if (size <= 0 || static_cast<std::size_t>(size) > kMaxPacketBytes)
      src_.fail_at(at + 4, "absurd packet size " + std::to_string(size));
    const std::uint64_t room = std::min(end, src_.size()) - src_.offset();
    if (static_cast<std::uint64_t>(size) > room)
      src_.fail_at(at, "truncated packet: needs " + std::to_string(size) + " bytes, " + std::to_string(room) +
                           (end <= src_.size() ? " remain before the data table" : " remain in the file"));
    if (stream != event_stream_) {
      src_.seek(src_.offset() + static_cast<std::uint64_t>(size));
      return true;
    }
    packet_.resize(static_cast<std::size_t>(size));
    src_.read_exact(packet_.data(), packet_.size(), "packet");
    std::string problem;
    if (!decompress(codec_, packet_.data(), packet_.size(), kMaxDecompressedBytes, plain_, problem))
      src_.fail_at(at + 8, problem);
    try {
      parse_event_packet(out);
    } catch (const flat::FlatError& e) {
      src_.fail_at(at + 8, std::string("malformed event packet: ") + e.what());
    }
    return true;
  }

 private:
  void read_header() {
    char magic[14];
    src_.read_exact(magic, 14, "AEDAT 4.0 magic");
    if (std::memcmp(magic, kAedat4Magic, 14) != 0) src_.fail_at(0, "not an AEDAT 4.0 file (bad magic)");
    unsigned char size_le[4];
    src_.read_exact(size_le, 4, "header size");
    const std::uint32_t size = load_le<std::uint32_t>(size_le);
    if (size < 8 || size > kMaxHeaderBytes) src_.fail_at(14, "absurd header size " + std::to_string(size));
    std::vector<unsigned char> hdr(size);
    src_.read_exact(hdr.data(), size, "IOHeader");
    first_packet_ = src_.offset();
    std::string xml;
    try {
      flat::Table t = flat::root(hdr.data(), hdr.size());
      const std::int32_t compression = flat::field_i32(t, 0, 0);
      data_table_ = flat::field_i64(t, 1, -1);
      xml = flat::field_string(t, 2, kMaxHeaderBytes).value_or("");
      switch (compression) {
        case 0: codec_ = Codec::none; break;
        case 1: case 2: codec_ = Codec::lz4; break;
        case 3: case 4: codec_ = Codec::zstd; break;
        default: src_.fail_at(18, "unknown compression type " + std::to_string(compression));
      }
    } catch (const flat::FlatError& e) {
      src_.fail_at(18, std::string("malformed IOHeader: ") + e.what());
    }
    if (data_table_ >= 0 && static_cast<std::uint64_t>(data_table_) < first_packet_)
      src_.fail_at(18, "data table position " + std::to_string(data_table_) + " lies inside the header");
    streams_ = parse_aedat4_info_node(xml);
    for (const auto& [id, s] : streams_)
      if (s.type == "EVTS") {
        event_stream_ = id;
        info_.width = s.width;
        info_.height = s.height;
        break;
      }
    if (event_stream_ < 0) src_.fail_at(18, "the header declares no event stream (typeIdentifier EVTS)");
  }

  void parse_event_packet(std::vector<Event>& out) {
    const unsigned char* p = plain_.data();
    std::size_t n = plain_.size();
    // Size-prefixed (what DV writes) or bare; the file identifier tells which.
    if (n >= 12 && std::memcmp(p + 8, "EVTS", 4) == 0) {
      const std::uint32_t body = load_le<std::uint32_t>(p);
      if (body > n - 4) throw flat::FlatError("size prefix " + std::to_string(body) + " exceeds the packet");
      p += 4;
      n = body;
    } else if (!(n >= 8 && std::memcmp(p + 4, "EVTS", 4) == 0)) {
      throw flat::FlatError("payload of the event stream is not an EVTS packet");
    }
    flat::Table t = flat::root(p, n);
    auto v = flat::field_vector(t, 0, kEventBytes);
    if (!v) return;
    out.reserve(out.size() + v->second);
    std::uint64_t bad_xy = 0;
    for (std::size_t i = 0; i < v->second; ++i) {
      const unsigned char* e = p + v->first + i * kEventBytes;
      const std::int16_t x = load_le<std::int16_t>(e + 8), y = load_le<std::int16_t>(e + 10);
      if (x < 0 || y < 0) {
        ++bad_xy;
        continue;
      }
      out.push_back({load_le<std::int64_t>(e), static_cast<std::uint16_t>(x), static_cast<std::uint16_t>(y),
                     static_cast<std::uint8_t>(e[12] != 0)});
    }
    warn_skipped(src_.offset(), "events with negative coordinates (dropped)", bad_xy);
  }

  void load_table() {
    table_loaded_ = true;
    if (data_table_ < 0 || static_cast<std::uint64_t>(data_table_) >= src_.size()) return;
    const std::uint64_t n = src_.size() - static_cast<std::uint64_t>(data_table_);
    if (n > kMaxPacketBytes) return;
    const std::uint64_t back = src_.offset();
    std::vector<unsigned char> packed(static_cast<std::size_t>(n)), plain;
    src_.seek(static_cast<std::uint64_t>(data_table_));
    src_.read_exact(packed.data(), packed.size(), "data table");
    src_.seek(back);
    std::string problem;
    if (!decompress(codec_, packed.data(), packed.size(), kMaxDecompressedBytes, plain, problem)) return;
    if (plain.size() < 12 || std::memcmp(plain.data() + 8, "FTAB", 4) != 0) return;
    std::vector<std::pair<std::uint64_t, std::int64_t>> table;
    try {
      const unsigned char* p = plain.data() + 4;
      const std::size_t size = plain.size() - 4;
      auto defs = flat::field_vector(flat::root(p, size), 0, 4);
      if (!defs) return;
      for (std::size_t i = 0; i < defs->second; ++i) {
        flat::Table d = flat::table_at(p, size, defs->first + 4 * i);
        auto info = flat::field(d, 1, 8);
        const std::int64_t offset = flat::field_i64(d, 0, -1);
        if (!info || load_le<std::int32_t>(p + *info) != event_stream_) continue;
        if (offset < static_cast<std::int64_t>(first_packet_ + 8) || offset >= data_table_) return;
        table.emplace_back(static_cast<std::uint64_t>(offset), flat::field_i64(d, 4, INT64_MAX));
      }
    } catch (const flat::FlatError&) {
      return;
    }
    table_ = std::move(table);
  }

  bool table_loaded_ = false;
  std::vector<std::pair<std::uint64_t, std::int64_t>> table_;  // event packets: payload offset, last t
  Codec codec_ = Codec::none;
  std::int64_t data_table_ = -1;
  std::uint64_t first_packet_ = 0;
  std::map<int, Aedat4Stream> streams_;
  int event_stream_ = -1;
  std::vector<unsigned char> packet_, plain_;
};

}  // namespace

// The XML is DV's config tree: <node name="ID" path=".../outInfo/ID/"> holds
// <attr key="typeIdentifier">, and its child node "info" holds sizeX/sizeY.
std::map<int, Aedat4Stream> parse_aedat4_info_node(const std::string& xml) {
  std::map<int, Aedat4Stream> streams;
  int current = -1;
  std::size_t at = 0;
  while (at < xml.size()) {
    const std::size_t node = xml.find("<node", at), attr = xml.find("<attr", at);
    if (node == std::string::npos && attr == std::string::npos) break;
    if (node < attr) {
      const std::size_t tag_end = xml.find('>', node);
      const std::string tag = xml.substr(node, tag_end == std::string::npos ? std::string::npos : tag_end - node);
      const std::size_t o = tag.find("outInfo/");
      if (o != std::string::npos) {
        int id = -1;
        const char* b = tag.data() + o + 8;
        auto [p, ec] = std::from_chars(b, tag.data() + tag.size(), id);
        if (ec == std::errc() && p != b && id >= 0) {
          current = id;
          streams[current];
        }
      }
      at = tag_end == std::string::npos ? xml.size() : tag_end + 1;
      continue;
    }
    const std::size_t tag_end = xml.find('>', attr);
    if (tag_end == std::string::npos) break;
    const std::string tag = xml.substr(attr, tag_end - attr);
    std::size_t next = tag_end + 1;
    const std::string value = attr_value(xml, tag_end + 1, next);
    if (current >= 0) {
      Aedat4Stream& s = streams[current];
      if (tag.find("key=\"typeIdentifier\"") != std::string::npos) s.type = value;
      if (tag.find("key=\"sizeX\"") != std::string::npos) s.width = to_int(value);
      if (tag.find("key=\"sizeY\"") != std::string::npos) s.height = to_int(value);
    }
    at = next;
  }
  return streams;
}

std::unique_ptr<EventReader> open_aedat4(const std::string& path) { return std::make_unique<Aedat4Reader>(path); }

}  // namespace yelan::camera
