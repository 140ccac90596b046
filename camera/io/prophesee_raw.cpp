#include "camera/io/prophesee_raw.h"

#include <array>
#include <charconv>

#include "camera/io/byte_source_reader.h"

namespace yelan::camera {
namespace {

bool parse_int(std::string_view s, int& v) {
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  return ec == std::errc() && p == s.data() + s.size() && v > 0 && v <= 65536;
}

// `WxH`
bool parse_geometry(std::string_view s, int& w, int& h) {
  auto x = s.find('x');
  return x != std::string_view::npos && parse_int(s.substr(0, x), w) && parse_int(s.substr(x + 1), h);
}

// Sensor size of the plugins whose files carry no geometry line (older Metavision).
void size_from_plugin(const std::string& plugin, int& w, int& h) {
  if (plugin.find("gen41") != std::string::npos || plugin.find("gen4") != std::string::npos ||
      plugin.find("imx636") != std::string::npos) {
    w = 1280, h = 720;
  } else if (plugin.find("gen3") != std::string::npos) {
    w = 640, h = 480;
  } else if (plugin.find("genx320") != std::string::npos) {
    w = 320, h = 320;
  }
}

void apply_header_line(std::string_view line, RawHeader& h, std::string& plugin) {
  auto sp = line.find(' ');
  std::string_view key = line.substr(0, sp);
  std::string_view val = sp == std::string_view::npos ? std::string_view{} : line.substr(sp + 1);
  while (!val.empty() && (val.back() == '\r' || val.back() == ' ')) val.remove_suffix(1);
  if (key == "evt") {
    h.evt = std::string(val);
  } else if (key == "geometry") {
    int w = 0, hh = 0;
    if (parse_geometry(val, w, hh)) h.width = w, h.height = hh;
  } else if (key == "format") {
    // e.g. "EVT3;height=720;width=1280"
    std::string_view name = val.substr(0, val.find(';'));
    if (name == "EVT3") h.evt = "3.0";
    else if (name == "EVT21") h.evt = "2.1";
    else if (name == "EVT2") h.evt = "2.0";
    for (std::size_t at = val.find(';'); at != std::string_view::npos; at = val.find(';', at + 1)) {
      std::string_view kv = val.substr(at + 1, val.find(';', at + 1) - at - 1);
      int v = 0;
      if (kv.rfind("width=", 0) == 0 && parse_int(kv.substr(6), v)) h.width = v;
      if (kv.rfind("height=", 0) == 0 && parse_int(kv.substr(7), v)) h.height = v;
    }
  } else if (key == "plugin_name") {
    plugin = std::string(val);
  }
}

// Decoders keep their state between blocks of words, so a file is read in bounded pieces.
class RawReader : public ByteSourceReader {
 public:
  RawReader(const std::string& path, const RawHeader& h, std::size_t word_bytes, const char* format)
      : ByteSourceReader(path), header_(h), word_bytes_(word_bytes) {
    info_.format = format;
    info_.width = h.width;
    info_.height = h.height;
  }

 protected:
  void restart() override {
    src_.seek(header_.data_offset);
    have_time_ = false;
    epoch_ = last_raw_ = 0;
    time_high_ = -1;
    reset_state();
  }
  bool decode(std::vector<Event>& out) override {
    const std::size_t got = src_.read_some(block_.data(), block_.size());
    const std::size_t whole = got - got % word_bytes_;
    block_offset_ = src_.offset() - got;
    if (whole < got)
      warn_skipped(block_offset_ + whole, "file ends inside a " + std::to_string(word_bytes_) +
                                              "-byte word (" + std::to_string(got - whole) +
                                              " bytes ignored)");
    decode_block(block_.data(), whole, out);
    return got == block_.size();
  }
  virtual void reset_state() = 0;  // the format's own decoder state
  virtual void decode_block(const unsigned char* p, std::size_t n, std::vector<Event>& out) = 0;

  // Extends a timer of `bits` bits to 64 bits: a step back of more than half the range is a
  // wrap of the sensor's counter, a smaller one is left as it is (the base reports it).
  std::int64_t unwrap(std::int64_t raw, int bits) {
    const std::int64_t range = std::int64_t{1} << bits;
    if (have_time_ && raw + epoch_ < last_raw_ - range / 2) {
      epoch_ += range;
      // Only a hostile file wraps this often; stop before the 64-bit time overflows.
      if (epoch_ > (std::int64_t{1} << 50)) src_.fail("the sensor timer wraps too often (corrupt time words?)");
    }
    have_time_ = true;
    last_raw_ = raw + epoch_;
    return last_raw_;
  }

  RawHeader header_;
  std::size_t word_bytes_;
  std::array<unsigned char, 1 << 16> block_{};
  std::uint64_t block_offset_ = 0;
  bool have_time_ = false;
  std::int64_t epoch_ = 0, last_raw_ = 0;
  std::int64_t time_high_ = -1;  // the unwrapped high bits of the time; -1 until a time word
};

// EVT 2.0 and 2.1 share their grammar: a 4-bit word type on top; CD words (types 0 and 1, the
// polarity) carry the 6 low bits of the time, EV_TIME_HIGH (type 8) the upper 28 bits of the
// 34-bit timer; trigger (A), other (E) and continued (F) words carry no CD event. A Format
// says how wide a word is and what its CD word holds.
template <class Format>
class Evt2FamilyReader final : public RawReader {
 public:
  using Word = typename Format::Word;
  explicit Evt2FamilyReader(const std::string& path, const RawHeader& h)
      : RawReader(path, h, sizeof(Word), Format::kName) {
    restart();  // not from RawReader: reset_state() is not callable there yet
  }

 protected:
  void reset_state() override {}
  void decode_block(const unsigned char* p, std::size_t n, std::vector<Event>& out) override {
    std::uint64_t no_time = 0, unknown = 0;
    for (std::size_t i = 0; i < n; i += sizeof(Word)) {
      const Word w = load_le<Word>(p + i);
      const unsigned type = static_cast<unsigned>(w >> (8 * sizeof(Word) - 4));
      switch (type) {
        case 0x0:
        case 0x1:
          if (time_high_ < 0) ++no_time;
          else Format::cd(w, time_high_, static_cast<std::uint8_t>(type), out);
          break;
        case 0x8:
          time_high_ = unwrap(Format::time_high(w), 28) << 6;
          break;
        case 0xA:
        case 0xE:
        case 0xF:
          break;
        default:
          ++unknown;
      }
    }
    warn_skipped(block_offset_, std::string("CD events before the first ") + Format::kTimeHigh + " (dropped)", no_time);
    warn_skipped(block_offset_, std::string("reserved ") + Format::kLabel + " word types (skipped)", unknown);
  }
};

// EVT 2.0: 32-bit words; a CD word holds 6 time bits, x and y of one pixel.
struct Evt20 {
  using Word = std::uint32_t;
  static constexpr const char* kName = "evt2";
  static constexpr const char* kLabel = "EVT 2.0";
  static constexpr const char* kTimeHigh = "EV_TIME_HIGH";
  static std::int64_t time_high(Word w) { return w & 0x0FFFFFFF; }
  static void cd(Word w, std::int64_t time_high, std::uint8_t p, std::vector<Event>& out) {
    out.push_back({time_high | ((w >> 22) & 0x3F), static_cast<std::uint16_t>((w >> 11) & 0x7FF),
                   static_cast<std::uint16_t>(w & 0x7FF), p});
  }
};

// EVT 2.1: 64-bit words (read as little-endian 64-bit values, the layout Metavision writes
// to files); a CD word holds 6 time bits, x aligned to 32, y, and a 32-bit mask of which of
// the 32 pixels from x fired.
struct Evt21 {
  using Word = std::uint64_t;
  static constexpr const char* kName = "evt21";
  static constexpr const char* kLabel = "EVT 2.1";
  static constexpr const char* kTimeHigh = "EVT_TIME_HIGH";
  static std::int64_t time_high(Word w) { return static_cast<std::int64_t>((w >> 32) & 0x0FFFFFFF); }
  static void cd(Word w, std::int64_t time_high, std::uint8_t p, std::vector<Event>& out) {
    const std::int64_t t = time_high | static_cast<std::int64_t>((w >> 54) & 0x3F);
    const unsigned x0 = static_cast<unsigned>((w >> 43) & 0x7FF);
    const auto y = static_cast<std::uint16_t>((w >> 32) & 0x7FF);
    for (std::uint32_t mask = static_cast<std::uint32_t>(w); mask; mask &= mask - 1)
      out.push_back({t, static_cast<std::uint16_t>(x0 + static_cast<unsigned>(__builtin_ctz(mask))), y, p});
  }
};

// EVT 3.0: 16-bit words that update a decoder state (y, base x, polarity, 24-bit time);
// events are emitted by ADDR_X (one) and VECT_12/VECT_8 (a mask from the base x).
class Evt3Reader final : public RawReader {
 public:
  explicit Evt3Reader(const std::string& path, const RawHeader& h) : RawReader(path, h, 2, "evt3") {
    restart();  // not from RawReader: reset_state() is not callable there yet
  }

 protected:
  void reset_state() override {
    time_ = 0;
    y_ = base_x_ = 0;
    pol_ = 0;
    have_y_ = false;
  }
  void decode_block(const unsigned char* p, std::size_t n, std::vector<Event>& out) override {
    std::uint64_t no_state = 0, unknown = 0;
    for (std::size_t i = 0; i < n; i += 2) {
      const std::uint16_t w = load_le<std::uint16_t>(p + i);
      const unsigned v = w & 0xFFF;
      switch (w >> 12) {
        case 0x0:  // EVT_ADDR_Y
          y_ = static_cast<std::uint16_t>(v & 0x7FF);
          have_y_ = true;
          break;
        case 0x2:  // EVT_ADDR_X: one event
          if (!ready()) {
            ++no_state;
            break;
          }
          out.push_back({time_, static_cast<std::uint16_t>(v & 0x7FF), y_, static_cast<std::uint8_t>(v >> 11)});
          break;
        case 0x3:  // VECT_BASE_X
          base_x_ = v & 0x7FF;
          pol_ = static_cast<std::uint8_t>(v >> 11);
          break;
        case 0x4:  // VECT_12
          emit_vector(v, 12, no_state, out);
          break;
        case 0x5:  // VECT_8
          emit_vector(v & 0xFF, 8, no_state, out);
          break;
        case 0x6:  // EVT_TIME_LOW
          if (time_high_ >= 0) time_ = time_high_ | v;
          break;
        case 0x8:  // EVT_TIME_HIGH
          time_high_ = unwrap(v, 12) << 12;
          time_ = time_high_;
          break;
        case 0x7:  // CONTINUED_4
        case 0xA:  // EXT_TRIGGER
        case 0xE:  // OTHERS
        case 0xF:  // CONTINUED_12
          break;
        default:
          ++unknown;
      }
    }
    warn_skipped(block_offset_, "events before the first EVT_TIME_HIGH / EVT_ADDR_Y (dropped)", no_state);
    warn_skipped(block_offset_, "reserved EVT 3.0 word types (skipped)", unknown);
  }

 private:
  bool ready() const { return time_high_ >= 0 && have_y_; }
  void emit_vector(unsigned mask, unsigned width, std::uint64_t& no_state, std::vector<Event>& out) {
    if (!ready()) {
      no_state += static_cast<std::uint64_t>(__builtin_popcount(mask));
    } else {
      for (; mask; mask &= mask - 1) {
        const unsigned bit = static_cast<unsigned>(__builtin_ctz(mask));
        out.push_back({time_, static_cast<std::uint16_t>(base_x_ + bit), y_, pol_});
      }
    }
    base_x_ += width;
  }

  std::int64_t time_ = 0;
  std::uint16_t y_ = 0;
  unsigned base_x_ = 0;
  std::uint8_t pol_ = 0;
  bool have_y_ = false;
};

}  // namespace

RawHeader parse_raw_header(const std::string& path) {
  ByteSource src(path);
  RawHeader h;
  std::string plugin, line;
  std::uint64_t at = 0;
  bool at_line_start = true;
  unsigned char c = 0;
  // Header lines start with '%'; the first line that does not (or `% end`) ends the header.
  while (true) {
    if (at_line_start) {
      if (src.read_some(&c, 1) != 1) break;
      if (c != '%') break;
      line.clear();
      at_line_start = false;
      continue;
    }
    if (src.read_some(&c, 1) != 1) src.fail("file ends inside the header line that starts at offset " + std::to_string(at));
    if (c == '\n') {
      std::string_view l(line);
      while (!l.empty() && l.front() == ' ') l.remove_prefix(1);
      if (l == "end" || l == "end\r") {
        at = src.offset();
        h.data_offset = at;
        break;
      }
      apply_header_line(l, h, plugin);
      at = src.offset();
      h.data_offset = at;
      at_line_start = true;
    } else {
      if (line.size() > 4096) src.fail_at(at, "header line longer than 4096 bytes");
      line.push_back(static_cast<char>(c));
    }
  }
  if (h.width == 0 && !plugin.empty()) size_from_plugin(plugin, h.width, h.height);
  return h;
}

std::unique_ptr<EventReader> open_prophesee_raw(const std::string& path) {
  RawHeader h = parse_raw_header(path);
  if (h.evt == "2.0" || h.evt == "2") return std::make_unique<Evt2FamilyReader<Evt20>>(path, h);
  if (h.evt == "2.1") return std::make_unique<Evt2FamilyReader<Evt21>>(path, h);
  if (h.evt == "3.0" || h.evt == "3") return std::make_unique<Evt3Reader>(path, h);
  throw FormatError(path, 0,
                    h.evt.empty() ? "Prophesee RAW header names no event format (no `% evt` or `% format` line)"
                                  : "unsupported Prophesee event format '" + h.evt + "'");
}

}  // namespace yelan::camera
