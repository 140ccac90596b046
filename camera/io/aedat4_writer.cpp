// AEDAT 4.0 writer: one event stream (id 0, EVTS), LZ4-frame packets of up to kPacketEvents
// events, and the FileDataTable (FTAB) at the end with dataTablePosition patched into the
// header, the layout DV itself writes so iniVation's tools can seek in our files.
#include <cerrno>
#include <cstdio>
#include <cstring>

#include "camera/io/aedat4.h"
#include "camera/io/compression.h"
#include "camera/io/event_writer.h"

namespace yelan::camera {
namespace {

constexpr std::size_t kPacketEvents = 8192;

void put32(std::vector<unsigned char>& b, std::size_t at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) b[at + static_cast<std::size_t>(i)] = static_cast<unsigned char>(v >> (8 * i));
}
void put16(std::vector<unsigned char>& b, std::size_t at, std::uint16_t v) {
  b[at] = static_cast<unsigned char>(v);
  b[at + 1] = static_cast<unsigned char>(v >> 8);
}
void put64(std::vector<unsigned char>& b, std::size_t at, std::uint64_t v) {
  for (int i = 0; i < 8; ++i) b[at + static_cast<std::size_t>(i)] = static_cast<unsigned char>(v >> (8 * i));
}

// Size-prefixed IOHeader: [size][root][IOHE][vtable 10+2][table: soffset, compression,
// dataTablePosition, infoNode offset][string]. dataTablePosition sits at byte 32 of it.
constexpr std::size_t kDataTableField = 32;
std::vector<unsigned char> io_header(std::int64_t data_table, const std::string& xml) {
  const std::size_t str_at = 44;
  std::size_t total = str_at + 4 + xml.size() + 1;
  total = (total + 7) / 8 * 8;
  std::vector<unsigned char> b(total, 0);
  put32(b, 0, static_cast<std::uint32_t>(total - 4));
  put32(b, 4, 24 - 4);  // root table at 24, relative to byte 4
  std::memcpy(b.data() + 8, "IOHE", 4);
  put16(b, 12, 10);  // vtable bytes
  put16(b, 14, 20);  // table bytes
  put16(b, 16, 4);   // compression
  put16(b, 18, 8);   // dataTablePosition
  put16(b, 20, 16);  // infoNode
  put32(b, 24, 24 - 12);
  put32(b, 28, 1);  // LZ4
  put64(b, kDataTableField, static_cast<std::uint64_t>(data_table));
  put32(b, 40, static_cast<std::uint32_t>(str_at - 40));
  put32(b, str_at, static_cast<std::uint32_t>(xml.size()));
  std::memcpy(b.data() + str_at + 4, xml.data(), xml.size());
  return b;
}

// The head of a size-prefixed flatbuffer whose root table holds one field, a vector at
// byte `vector_at`: [size][root offset][4-char identifier][vtable: 6 bytes, table 8 bytes,
// field at 4][table: soffset to the vtable, offset to the vector].
void one_vector_table(std::vector<unsigned char>& b, const char* identifier, std::size_t vector_at) {
  put32(b, 0, static_cast<std::uint32_t>(b.size() - 4));
  put32(b, 4, 20 - 4);
  std::memcpy(b.data() + 8, identifier, 4);
  put16(b, 12, 6);
  put16(b, 14, 8);
  put16(b, 16, 4);
  put32(b, 20, 20 - 12);
  put32(b, 24, static_cast<std::uint32_t>(vector_at - 24));
}

// Size-prefixed EventPacket: [size][root][EVTS][vtable 6+2][table: soffset, elements
// offset][count][16-byte events], the event array 8-byte aligned.
std::vector<unsigned char> event_packet(std::span<const Event> ev) {
  std::vector<unsigned char> b(32 + 16 * ev.size(), 0);
  one_vector_table(b, "EVTS", 28);
  put32(b, 28, static_cast<std::uint32_t>(ev.size()));
  for (std::size_t i = 0; i < ev.size(); ++i) {
    const std::size_t at = 32 + 16 * i;
    put64(b, at, static_cast<std::uint64_t>(ev[i].t));
    put16(b, at + 8, ev[i].x);
    put16(b, at + 10, ev[i].y);
    b[at + 12] = ev[i].p ? 1 : 0;
  }
  return b;
}

struct PacketEntry {
  std::int64_t offset;  // of the payload, after the 8-byte packet header
  std::int32_t size;
  std::int64_t count, t_start, t_end;
};

// Size-prefixed FileDataTable: root table -> vector of FileDataDefinition tables sharing one
// vtable {byte_offset, packet_info{stream id, size}, num_elements, timestamp_start, timestamp_end}.
std::vector<unsigned char> data_table(const std::vector<PacketEntry>& entries) {
  const std::size_t n = entries.size();
  const std::size_t vec_at = 28, defs_vt = (vec_at + 4 + 4 * n + 3) / 4 * 4;
  std::size_t first_def = defs_vt + 16;
  if (first_def % 8 != 4) first_def += 4;
  std::vector<unsigned char> b(first_def + 48 * n, 0);
  one_vector_table(b, "FTAB", vec_at);
  put32(b, vec_at, static_cast<std::uint32_t>(n));
  put16(b, defs_vt, 14);
  put16(b, defs_vt + 2, 44);
  put16(b, defs_vt + 4, 4);
  put16(b, defs_vt + 6, 12);
  put16(b, defs_vt + 8, 20);
  put16(b, defs_vt + 10, 28);
  put16(b, defs_vt + 12, 36);
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t slot = vec_at + 4 + 4 * i, t = first_def + 48 * i;
    put32(b, slot, static_cast<std::uint32_t>(t - slot));
    put32(b, t, static_cast<std::uint32_t>(t - defs_vt));
    put64(b, t + 4, static_cast<std::uint64_t>(entries[i].offset));
    put32(b, t + 12, 0);
    put32(b, t + 16, static_cast<std::uint32_t>(entries[i].size));
    put64(b, t + 20, static_cast<std::uint64_t>(entries[i].count));
    put64(b, t + 28, static_cast<std::uint64_t>(entries[i].t_start));
    put64(b, t + 36, static_cast<std::uint64_t>(entries[i].t_end));
  }
  return b;
}

std::string info_xml(const StreamInfo& info) {
  return "<dv version=\"2.0\">\n"
         "    <node name=\"outInfo\" path=\"/mainloop/Recorder/outInfo/\">\n"
         "        <node name=\"0\" path=\"/mainloop/Recorder/outInfo/0/\">\n"
         "            <attr key=\"compression\" type=\"string\">LZ4</attr>\n"
         "            <attr key=\"originalModuleName\" type=\"string\">yelan</attr>\n"
         "            <attr key=\"originalOutputName\" type=\"string\">events</attr>\n"
         "            <attr key=\"typeDescription\" type=\"string\">Array of events (polarity ON/OFF).</attr>\n"
         "            <attr key=\"typeIdentifier\" type=\"string\">EVTS</attr>\n"
         "            <node name=\"info\" path=\"/mainloop/Recorder/outInfo/0/info/\">\n"
         "                <attr key=\"sizeX\" type=\"int\">" + std::to_string(info.width) + "</attr>\n"
         "                <attr key=\"sizeY\" type=\"int\">" + std::to_string(info.height) + "</attr>\n"
         "                <attr key=\"source\" type=\"string\">yelan</attr>\n"
         "                <attr key=\"tsOffset\" type=\"long\">0</attr>\n"
         "            </node>\n"
         "        </node>\n"
         "    </node>\n"
         "</dv>\n";
}

class Aedat4Writer final : public EventWriter {
 public:
  Aedat4Writer(const std::string& path, const StreamInfo& info) : tmp_(path) {
    file_.reset(std::fopen(tmp_.path().c_str(), "wb"));
    if (!file_) throw std::runtime_error("cannot create " + tmp_.path() + ": " + std::strerror(errno));
    header_ = io_header(-1, info_xml(info));
    put(kAedat4Magic, 14);
    put(header_.data(), header_.size());
  }

  void write(std::span<const Event> events) override {
    for (const Event& e : events) {
      buf_.push_back(e);
      if (buf_.size() == kPacketEvents) flush();
    }
  }

  void close() override {
    flush();
    const std::int64_t table_at = offset_;
    const auto table = data_table(entries_);
    const auto packed = compress_lz4_frame(table.data(), table.size());
    put(packed.data(), packed.size());
    put64(header_, kDataTableField, static_cast<std::uint64_t>(table_at));
    if (std::fseek(file_.get(), 14, SEEK_SET) != 0) fail();
    if (std::fwrite(header_.data(), 1, header_.size(), file_.get()) != header_.size()) fail();
    std::FILE* f = file_.release();
    if (std::fclose(f) != 0) throw std::runtime_error("cannot write " + tmp_.path());
    tmp_.commit();
  }

 private:
  void flush() {
    if (buf_.empty()) return;
    const auto plain = event_packet(buf_);
    const auto packed = compress_lz4_frame(plain.data(), plain.size());
    unsigned char head[8];
    const std::int32_t stream = 0, size = static_cast<std::int32_t>(packed.size());
    std::memcpy(head, &stream, 4);
    std::memcpy(head + 4, &size, 4);
    put(head, 8);
    entries_.push_back({offset_, size, static_cast<std::int64_t>(buf_.size()), buf_.front().t, buf_.back().t});
    put(packed.data(), packed.size());
    buf_.clear();
  }
  void put(const void* p, std::size_t n) {
    if (std::fwrite(p, 1, n, file_.get()) != n) fail();
    offset_ += static_cast<std::int64_t>(n);
  }
  [[noreturn]] void fail() { throw std::runtime_error("cannot write " + tmp_.path() + ": " + std::strerror(errno)); }

  struct Closer {
    void operator()(std::FILE* f) const { std::fclose(f); }
  };
  TempFile tmp_;
  std::unique_ptr<std::FILE, Closer> file_;
  std::vector<unsigned char> header_;
  std::vector<Event> buf_;
  std::vector<PacketEntry> entries_;
  std::int64_t offset_ = 0;
};

}  // namespace

std::unique_ptr<EventWriter> open_aedat4_writer(const std::string& path, const StreamInfo& info) {
  return std::make_unique<Aedat4Writer>(path, info);
}

}  // namespace yelan::camera
