// NumPy .npy structured arrays of events: a 1-D array whose dtype has integer fields t, x,
// y, p (any widths and byte orders; `ts`/`timestamp` and `polarity`/`pol` are accepted too),
// as expelliarmus and tonic save them. Read in record blocks.
#include <array>
#include <charconv>
#include <cstring>

#include "camera/io/byte_source_reader.h"
#include "camera/io/readers.h"

namespace yelan::camera {
namespace {

struct Field {
  std::size_t offset = 0, size = 0;
  bool is_signed = false, big_endian = false, present = false;
};

std::int64_t load_field(const unsigned char* rec, const Field& f) {
  unsigned char b[8] = {};
  for (std::size_t i = 0; i < f.size; ++i) b[i] = f.big_endian ? rec[f.offset + f.size - 1 - i] : rec[f.offset + i];
  std::uint64_t u = load_le<std::uint64_t>(b);
  if (f.is_signed && f.size < 8 && (u >> (8 * f.size - 1)) & 1) u |= ~std::uint64_t{0} << (8 * f.size);
  return static_cast<std::int64_t>(u);
}

class NpyReader final : public ByteSourceReader {
 public:
  explicit NpyReader(const std::string& path) : ByteSourceReader(path) {
    info_.format = "npy";
    parse_header();
    info_.events = count_;
    restart();
  }

 protected:
  void restart() override {
    src_.seek(data_offset_);
    next_ = 0;
  }

  bool decode(std::vector<Event>& out) override {
    if (next_ >= count_) return false;
    const std::uint64_t n = std::min<std::uint64_t>(count_ - next_, (1u << 20) / record_);
    buf_.resize(static_cast<std::size_t>(n * record_));
    src_.read_exact(buf_.data(), buf_.size(), "records");
    std::uint64_t bad = 0;
    for (std::uint64_t i = 0; i < n; ++i) {
      const unsigned char* rec = buf_.data() + i * record_;
      const std::int64_t x = load_field(rec, fields_[1]), y = load_field(rec, fields_[2]);
      if (x < 0 || y < 0 || x > 65535 || y > 65535) {
        ++bad;
        continue;
      }
      out.push_back({load_field(rec, fields_[0]), static_cast<std::uint16_t>(x), static_cast<std::uint16_t>(y),
                     static_cast<std::uint8_t>(load_field(rec, fields_[3]) > 0)});
    }
    warn_skipped(src_.offset(), "records with coordinates outside 0..65535 (dropped)", bad);
    next_ += n;
    return next_ < count_;
  }

 private:
  void parse_header() {
    unsigned char pre[10];
    src_.read_exact(pre, 10, "npy preamble");
    if (std::memcmp(pre, "\x93NUMPY", 6) != 0) src_.fail_at(0, "not a .npy file (bad magic)");
    if (pre[6] < 1 || pre[6] > 3) src_.fail_at(6, "unsupported .npy version " + std::to_string(pre[6]));
    std::uint64_t len = load_le<std::uint16_t>(pre + 8);
    if (pre[6] >= 2) {  // version 2 and 3: a 4-byte header length
      unsigned char l4[4] = {pre[8], pre[9], 0, 0};
      src_.read_exact(l4 + 2, 2, "npy header length");
      len = load_le<std::uint32_t>(l4);
    }
    if (len > (1u << 20)) src_.fail_at(8, "absurd .npy header length " + std::to_string(len));
    std::string h(static_cast<std::size_t>(len), '\0');
    src_.read_exact(h.data(), h.size(), ".npy header");
    data_offset_ = src_.offset();
    parse_dict(h);
  }

  void parse_dict(const std::string& h) {
    const std::uint64_t at = data_offset_ - h.size();
    if (h.find("'fortran_order': True") != std::string::npos) src_.fail_at(at, "Fortran-ordered arrays are not supported");
    const auto d = h.find("'descr':");
    const auto lb = h.find('[', d), rb = h.find(']', lb);
    if (d == std::string::npos || lb == std::string::npos || rb == std::string::npos)
      src_.fail_at(at, "the dtype is not a structured array of fields (t, x, y, p)");
    std::size_t offset = 0;
    for (std::size_t p = h.find('(', lb); p != std::string::npos && p < rb; p = h.find('(', p + 1)) {
      const auto q1 = h.find('\'', p), q2 = h.find('\'', q1 + 1), q3 = h.find('\'', q2 + 1), q4 = h.find('\'', q3 + 1);
      const auto close = h.find(')', p);
      if (close == std::string::npos || q4 == std::string::npos || q4 > close)
        src_.fail_at(at, "malformed dtype field in the .npy header");
      const std::string name = h.substr(q1 + 1, q2 - q1 - 1), type = h.substr(q3 + 1, q4 - q3 - 1);
      if (type.size() < 3) src_.fail_at(at, "malformed dtype '" + type + "'");
      std::size_t size = 0;
      auto [e, ec] = std::from_chars(type.data() + 2, type.data() + type.size(), size);
      if (ec != std::errc() || e != type.data() + type.size() || size == 0 || size > 64)
        src_.fail_at(at, "malformed dtype '" + type + "'");
      int slot = -1;
      if (name == "t" || name == "ts" || name == "timestamp") slot = 0;
      else if (name == "x") slot = 1;
      else if (name == "y") slot = 2;
      else if (name == "p" || name == "polarity" || name == "pol") slot = 3;
      if (slot >= 0) {
        const char kind = type[1];
        if ((kind != 'i' && kind != 'u' && kind != 'b') || size > 8)
          src_.fail_at(at, "field '" + name + "' has type '" + type + "'; integer fields are needed");
        fields_[static_cast<std::size_t>(slot)] = {offset, size, kind == 'i', type[0] == '>', true};
      }
      offset += size;
      p = close;
    }
    for (int k = 0; k < 4; ++k)
      if (!fields_[static_cast<std::size_t>(k)].present)
        src_.fail_at(at, std::string("the dtype lacks field '") + "txyp"[k] + "'");
    record_ = offset;
    const auto s = h.find("'shape':"), open = h.find('(', s);
    if (s == std::string::npos || open == std::string::npos) src_.fail_at(at, "the .npy header has no shape");
    std::size_t i = open + 1;
    while (i < h.size() && h[i] == ' ') ++i;
    auto [e, ec] = std::from_chars(h.data() + i, h.data() + h.size(), count_);
    if (ec != std::errc() || (*e != ',' && *e != ')')) src_.fail_at(at, "the array must be one-dimensional");
    if (*e == ',') {
      std::size_t j = static_cast<std::size_t>(e - h.data()) + 1;
      while (j < h.size() && h[j] == ' ') ++j;
      if (j < h.size() && h[j] != ')') src_.fail_at(at, "the array must be one-dimensional");
    }
    if (count_ > src_.remaining() / record_)
      src_.fail_at(data_offset_, "truncated: the header promises " + std::to_string(count_) + " records of " +
                                     std::to_string(record_) + " bytes, " + std::to_string(src_.remaining()) +
                                     " bytes remain");
  }

  std::array<Field, 4> fields_{};
  std::uint64_t data_offset_ = 0, count_ = 0, next_ = 0, record_ = 1;
  std::vector<unsigned char> buf_;
};

}  // namespace

std::unique_ptr<EventReader> open_npy_events(const std::string& path) { return std::make_unique<NpyReader>(path); }

}  // namespace yelan::camera
