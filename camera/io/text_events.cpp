// Text event files, one event per line: `t x y p`. With the header line `# t_us x y p`, t is
// integer microseconds (what we write); otherwise t is in seconds (the RPG/ESIM convention).
// `# geometry WxH`, or a first data line of just `W H` (rpg_e2vid), gives the sensor size.
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>

#include "camera/io/byte_source_reader.h"
#include "camera/io/event_writer.h"
#include "camera/io/readers.h"

namespace yelan::camera {
namespace {

constexpr std::size_t kMaxLine = 4096;

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

// Splits on spaces, tabs and commas; at most `max` fields (returns the count found).
std::size_t split(std::string_view s, std::string_view* f, std::size_t max) {
  std::size_t n = 0, i = 0;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t' || s[i] == ',')) ++i;
    if (i == s.size()) break;
    std::size_t j = i;
    while (j < s.size() && s[j] != ' ' && s[j] != '\t' && s[j] != ',') ++j;
    if (n == max) return max + 1;
    f[n++] = s.substr(i, j - i);
    i = j;
  }
  return n;
}

template <typename T>
bool parse_whole(std::string_view s, T& v) {
  auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  return ec == std::errc() && p == s.data() + s.size();
}

// Seconds as written ("12.3456789", "-0.5", "1e-3") to microseconds, rounded to nearest.
bool seconds_to_us(std::string_view s, std::int64_t& us) {
  if (s.find_first_of("eE") == std::string_view::npos) {
    bool neg = !s.empty() && s.front() == '-';
    if (neg) s.remove_prefix(1);
    const auto dot = s.find('.');
    std::string_view whole = s.substr(0, dot), frac = dot == std::string_view::npos ? "" : s.substr(dot + 1);
    std::int64_t w = 0;
    if (whole.empty()) w = 0;
    else if (!parse_whole(whole, w) || w < 0 || w > 9'000'000'000'000LL) return false;
    std::int64_t f = 0;
    int digits = 0;
    for (char c : frac) {
      if (c < '0' || c > '9') return false;
      if (digits < 6) f = f * 10 + (c - '0');
      else if (digits == 6 && c >= '5') f += 1;  // round half up on the 7th digit
      ++digits;
    }
    if (whole.empty() && frac.empty()) return false;
    for (int d = std::min(digits, 6); d < 6; ++d) f *= 10;
    us = w * 1'000'000 + f;
    if (neg) us = -us;
    return true;
  }
  double v = 0;
  if (!parse_whole(s, v) || !std::isfinite(v) || std::fabs(v) > 9e9) return false;
  us = std::llround(v * 1e6);
  return true;
}

class TextReader final : public ByteSourceReader {
 public:
  explicit TextReader(const std::string& path) : ByteSourceReader(path) {
    info_.format = "text";
    restart();
    scan_preamble();
  }

 protected:
  void restart() override {
    src_.seek(0);
    buf_.clear();
    pos_ = 0;
    buf_offset_ = 0;
    line_no_ = 0;
    done_ = false;
  }

  bool decode(std::vector<Event>& out) override {
    std::string_view line;
    std::uint64_t at = 0;
    for (int i = 0; i < 8192 && next_line(line, at); ++i) parse_line(line, at, out);
    return !done_;
  }

 private:
  // Reads the leading comments so info() knows the units and the sensor size up front.
  void scan_preamble() {
    std::string_view line;
    std::uint64_t at = 0;
    std::vector<Event> none;
    while (next_line(line, at)) {
      std::string_view t = trim(line);
      std::string_view f[4];
      if (!t.empty() && t.front() != '#') {
        if (split(t, f, 4) == 2) parse_line(line, at, none);
        break;
      }
      parse_line(line, at, none);
    }
    restart();
  }

  bool next_line(std::string_view& line, std::uint64_t& at) {
    while (true) {
      const std::size_t nl = buf_.find('\n', pos_);
      if (nl != std::string::npos) {
        line = std::string_view(buf_).substr(pos_, nl - pos_);
        at = buf_offset_ + pos_;
        pos_ = nl + 1;
        ++line_no_;
        return true;
      }
      if (buf_.size() - pos_ > kMaxLine) src_.fail_at(buf_offset_ + pos_, "text line longer than 4096 bytes");
      buf_offset_ += pos_;
      buf_.erase(0, pos_);
      pos_ = 0;
      char chunk[1 << 16];
      const std::size_t got = src_.read_some(chunk, sizeof chunk);
      if (got == 0) {
        if (buf_.empty()) {
          done_ = true;
          return false;
        }
        line = buf_;  // last line without a newline
        at = buf_offset_;
        pos_ = buf_.size();
        ++line_no_;
        return true;
      }
      if (std::memchr(chunk, '\0', got)) src_.fail_at(src_.offset() - got, "NUL byte in a text event file");
      buf_.append(chunk, got);
    }
  }

  void parse_line(std::string_view raw, std::uint64_t at, std::vector<Event>& out) {
    std::string_view line = trim(raw);
    if (line.empty()) return;
    if (line.front() == '#') {
      std::string_view c = trim(line.substr(1));
      if (line_no_ == 1 && c.rfind("t_us", 0) == 0) integer_us_ = true;
      if (c.rfind("geometry ", 0) == 0) {
        std::string_view g = trim(c.substr(9));
        auto x = g.find('x');
        int w = 0, h = 0;
        if (x != std::string_view::npos && parse_whole(g.substr(0, x), w) && parse_whole(g.substr(x + 1), h) &&
            w > 0 && h > 0 && w <= 65536 && h <= 65536)
          info_.width = w, info_.height = h;
      }
      return;
    }
    std::string_view f[4];
    const std::size_t n = split(line, f, 4);
    if (n == 2 && !seen_event_) {
      int w = 0, h = 0;
      if (parse_whole(f[0], w) && parse_whole(f[1], h) && w > 0 && h > 0 && w <= 65536 && h <= 65536) {
        info_.width = w, info_.height = h;
        return;
      }
    }
    if (n != 4)
      src_.fail_at(at, "line " + std::to_string(line_no_) + ": expected 4 fields `t x y p`, got " +
                           (n > 4 ? std::string("more") : std::to_string(n)));
    std::int64_t t = 0;
    bool ok_t = integer_us_ ? parse_whole(f[0], t) : seconds_to_us(f[0], t);
    if (!ok_t) src_.fail_at(at, "line " + std::to_string(line_no_) + ": bad timestamp '" + std::string(f[0]) + "'");
    long x = 0, y = 0, p = 0;
    if (!parse_whole(f[1], x) || !parse_whole(f[2], y) || x < 0 || y < 0 || x > 65535 || y > 65535)
      src_.fail_at(at, "line " + std::to_string(line_no_) + ": bad coordinates '" + std::string(f[1]) + " " +
                           std::string(f[2]) + "'");
    if (!parse_whole(f[3], p) || (p != 0 && p != 1 && p != -1))
      src_.fail_at(at, "line " + std::to_string(line_no_) + ": bad polarity '" + std::string(f[3]) + "'");
    seen_event_ = true;
    out.push_back({t, static_cast<std::uint16_t>(x), static_cast<std::uint16_t>(y), static_cast<std::uint8_t>(p == 1)});
  }

  std::string buf_;
  std::size_t pos_ = 0;
  std::uint64_t buf_offset_ = 0, line_no_ = 0;
  bool done_ = false, integer_us_ = false, seen_event_ = false;
};

class TextWriter final : public EventWriter {
 public:
  TextWriter(const std::string& path, const StreamInfo& info) : tmp_(path), path_(path) {
    file_.reset(std::fopen(tmp_.path().c_str(), "wb"));
    if (!file_) throw std::runtime_error("cannot create " + tmp_.path() + ": " + std::strerror(errno));
    std::fputs("# t_us x y p\n", file_.get());
    if (info.width > 0 && info.height > 0) std::fprintf(file_.get(), "# geometry %dx%d\n", info.width, info.height);
  }
  void write(std::span<const Event> events) override {
    char line[64];
    for (const Event& e : events) {
      auto n = std::snprintf(line, sizeof line, "%lld %u %u %u\n", static_cast<long long>(e.t), e.x, e.y, e.p ? 1u : 0u);
      std::fwrite(line, 1, static_cast<std::size_t>(n), file_.get());
    }
  }
  void close() override {
    std::FILE* f = file_.release();
    const bool bad = std::ferror(f) != 0;
    if (std::fclose(f) != 0 || bad) throw std::runtime_error("cannot write " + tmp_.path());
    tmp_.commit();
  }

 private:
  struct Closer {
    void operator()(std::FILE* f) const { std::fclose(f); }
  };
  TempFile tmp_;
  std::string path_;
  std::unique_ptr<std::FILE, Closer> file_;
};

}  // namespace

std::unique_ptr<EventReader> open_text_events(const std::string& path) { return std::make_unique<TextReader>(path); }

std::unique_ptr<EventWriter> open_text_writer(const std::string& path, const StreamInfo& info) {
  return std::make_unique<TextWriter>(path, info);
}

}  // namespace yelan::camera
