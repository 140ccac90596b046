// BVH reader: a line reader with a length cap feeds a token parser for the HIERARCHY and a
// per-line number parser for MOTION. Every failure names file, byte offset, line and what was
// expected; caps on joints, depth, frames and values keep bad headers from exhausting memory.
#include "camera/sim/bvh.h"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <string_view>

namespace yelan::camera::sim {

BvhError::BvhError(const std::string& file, std::uint64_t offset, long line, const std::string& problem)
    : FormatError(file, offset, "line " + std::to_string(line) + ": " + problem), line_(line) {}

int BvhClip::find(const std::string& name) const {
  for (std::size_t i = 0; i < joints.size(); ++i)
    if (joints[i].name == name) return int(i);
  return -1;
}

namespace {

constexpr std::size_t kMaxLine = 1 << 20;        // a frame of 4096 joints x 6 channels fits
constexpr int kMaxJoints = 4096;
constexpr int kMaxDepth = 256;
constexpr long kMaxFrames = 10'000'000;           // 23 h at 120 Hz
constexpr std::size_t kMaxValues = std::size_t(1) << 26;  // 512 MiB of doubles
constexpr double kMaxAbsValue = 1e7;              // larger offsets or angles are corrupt data

// Reads lines in bounded chunks (a file without newlines cannot make one huge string).
class LineReader {
 public:
  LineReader(const std::string& path) : path_(path), in_(path, std::ios::binary) {
    if (!in_) throw BvhError(path, 0, 0, "cannot open file");
  }
  // Next line without its terminator; false at end of file.
  bool next(std::string& line) {
    line.clear();
    if (eof_) return false;
    line_start_ = offset_;
    ++line_no_;
    for (;;) {
      if (pos_ == len_) {
        in_.read(buf_.data(), std::streamsize(buf_.size()));
        len_ = std::size_t(in_.gcount());
        pos_ = 0;
        if (len_ == 0) {
          eof_ = true;
          if (line.empty()) { --line_no_; return false; }
          break;
        }
      }
      const char* b = buf_.data() + pos_;
      const void* nl = std::memchr(b, '\n', len_ - pos_);
      std::size_t n = nl ? std::size_t(static_cast<const char*>(nl) - b) : len_ - pos_;
      if (line.size() + n > kMaxLine)
        throw BvhError(path_, line_start_, line_no_, "line longer than " + std::to_string(kMaxLine) + " bytes");
      line.append(b, n);
      pos_ += n;
      offset_ += n;
      if (nl) { ++pos_; ++offset_; break; }
    }
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return true;
  }
  long line_no() const { return line_no_; }
  std::uint64_t line_start() const { return line_start_; }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::ifstream in_;
  std::array<char, 1 << 16> buf_{};
  std::size_t pos_ = 0, len_ = 0;
  std::uint64_t offset_ = 0, line_start_ = 0;
  long line_no_ = 0;
  bool eof_ = false;
};

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }

struct Token {
  std::string_view text;
  std::uint64_t offset = 0;
  long line = 0;
};

// Whitespace tokens across lines, for the HIERARCHY section.
class Tokenizer {
 public:
  explicit Tokenizer(LineReader& r) : r_(r) {}
  // False at end of file.
  bool next(Token& t) {
    for (;;) {
      while (col_ < line_.size() && is_space(line_[col_])) ++col_;
      if (col_ < line_.size()) break;
      if (!r_.next(line_)) return false;
      col_ = 0;
    }
    std::size_t e = col_;
    while (e < line_.size() && !is_space(line_[e])) ++e;
    t = {std::string_view(line_).substr(col_, e - col_), r_.line_start() + col_, r_.line_no()};
    col_ = e;
    return true;
  }
  Token expect_any(const char* what) {
    Token t;
    if (!next(t)) throw BvhError(r_.path(), r_.line_start() + line_.size(), std::max(1L, r_.line_no()),
                                 std::string("unexpected end of file: expected ") + what);
    return t;
  }
  void expect(std::string_view word) {
    Token t = expect_any(std::string(word).c_str());
    if (t.text != word) fail(t, "expected '" + std::string(word) + "', found '" + std::string(t.text) + "'");
  }
  [[noreturn]] void fail(const Token& t, const std::string& problem) const {
    throw BvhError(r_.path(), t.offset, t.line, problem);
  }
  double number(const char* what) {
    Token t = expect_any(what);
    double v;
    if (!parse(t.text, v)) fail(t, std::string("expected ") + what + ", found '" + std::string(t.text) + "'");
    if (!(std::fabs(v) <= kMaxAbsValue)) fail(t, std::string("absurd ") + what + " " + std::string(t.text));
    return v;
  }
  bool line_done() const {
    std::size_t c = col_;
    while (c < line_.size() && is_space(line_[c])) ++c;
    return c == line_.size();
  }

  static bool parse(std::string_view s, double& v) {
    if (!s.empty() && s.front() == '+') s.remove_prefix(1);
    if (s.empty()) return false;
    auto [p, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
    return ec == std::errc() && p == s.data() + s.size() && std::isfinite(v);
  }

 private:
  LineReader& r_;
  std::string line_;
  std::size_t col_ = 0;
};

bool channel_from_name(std::string_view s, BvhChannel& c) {
  static constexpr std::array<std::pair<std::string_view, BvhChannel>, 6> names = {{
      {"Xposition", BvhChannel::Xposition}, {"Yposition", BvhChannel::Yposition},
      {"Zposition", BvhChannel::Zposition}, {"Xrotation", BvhChannel::Xrotation},
      {"Yrotation", BvhChannel::Yrotation}, {"Zrotation", BvhChannel::Zrotation}}};
  for (auto& [n, ch] : names)
    if (s == n) { c = ch; return true; }
  return false;
}

void parse_hierarchy(Tokenizer& tk, BvhClip& clip) {
  tk.expect("HIERARCHY");
  Token root = tk.expect_any("ROOT");
  if (root.text != "ROOT") tk.fail(root, "expected 'ROOT', found '" + std::string(root.text) + "'");
  std::vector<int> stack;       // open joints
  std::vector<bool> has_offset;
  auto open_joint = [&](const Token& at, std::string name, bool end_site) {
    if (int(clip.joints.size()) >= kMaxJoints) tk.fail(at, "more than " + std::to_string(kMaxJoints) + " joints");
    if (int(stack.size()) >= kMaxDepth) tk.fail(at, "hierarchy deeper than " + std::to_string(kMaxDepth));
    BvhJoint j;
    j.name = std::move(name);
    j.parent = stack.empty() ? -1 : stack.back();
    j.end_site = end_site;
    j.first_channel = clip.channel_count;
    clip.joints.push_back(std::move(j));
    has_offset.push_back(false);
    tk.expect("{");
    stack.push_back(int(clip.joints.size()) - 1);
  };
  open_joint(root, std::string(tk.expect_any("root name").text), false);
  while (!stack.empty()) {
    Token t = tk.expect_any("OFFSET, CHANNELS, JOINT, End Site or '}'");
    const int cur = stack.back();
    BvhJoint& j = clip.joints[cur];
    if (t.text == "OFFSET") {
      if (has_offset[cur]) tk.fail(t, "second OFFSET for joint '" + j.name + "'");
      for (int k = 0; k < 3; ++k) j.offset[k] = tk.number("OFFSET coordinate");
      has_offset[cur] = true;
    } else if (t.text == "CHANNELS") {
      if (j.end_site) tk.fail(t, "CHANNELS inside an End Site");
      if (!j.channels.empty()) tk.fail(t, "second CHANNELS for joint '" + j.name + "'");
      Token nt = tk.expect_any("channel count");
      double n;
      if (!Tokenizer::parse(nt.text, n) || n != std::floor(n) || n < 0 || n > 6)
        tk.fail(nt, "expected a channel count 0..6, found '" + std::string(nt.text) + "'");
      for (int k = 0; k < int(n); ++k) {
        Token ct = tk.expect_any("channel name");
        BvhChannel c;
        if (!channel_from_name(ct.text, c))
          tk.fail(ct, "expected a channel name (Xposition..Zrotation), found '" + std::string(ct.text) + "'");
        for (BvhChannel d : j.channels)
          if (d == c) tk.fail(ct, "channel " + std::string(ct.text) + " twice on joint '" + j.name + "'");
        j.channels.push_back(c);
      }
      j.first_channel = clip.channel_count;
      clip.channel_count += int(n);
    } else if (t.text == "JOINT") {
      if (j.end_site) tk.fail(t, "JOINT inside an End Site");
      open_joint(t, std::string(tk.expect_any("joint name").text), false);
    } else if (t.text == "End") {
      if (j.end_site) tk.fail(t, "End Site inside an End Site");
      tk.expect("Site");
      open_joint(t, j.name + "/End Site", true);
    } else if (t.text == "}") {
      if (!has_offset[cur]) tk.fail(t, "joint '" + clip.joints[cur].name + "' has no OFFSET");
      stack.pop_back();
    } else {
      tk.fail(t, "expected OFFSET, CHANNELS, JOINT, End Site or '}', found '" + std::string(t.text) + "'");
    }
  }
}

// "Frames: N" / "Frame Time: s" header lines; returns the value after the label.
std::string_view after_label(const std::string& line, std::string_view label) {
  std::string_view s(line);
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  if (s.substr(0, label.size()) != label) return {};
  s.remove_prefix(label.size());
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s.empty() ? std::string_view(" ") : s;  // non-empty marks "label found"
}

bool blank(const std::string& s) {
  for (char c : s)
    if (!is_space(c)) return false;
  return true;
}

void parse_motion(LineReader& r, BvhClip& clip) {
  std::string line;
  auto next_nonblank = [&](const char* what) {
    do {
      if (!r.next(line))
        throw BvhError(r.path(), r.line_start(), r.line_no(), std::string("unexpected end of file: expected ") + what);
    } while (blank(line));
  };
  next_nonblank("'Frames: N'");
  std::string_view v = after_label(line, "Frames:");
  double frames;
  if (v.empty()) throw BvhError(r.path(), r.line_start(), r.line_no(), "expected 'Frames: N'");
  if (!Tokenizer::parse(v, frames) || frames != std::floor(frames) || frames < 0)
    throw BvhError(r.path(), r.line_start(), r.line_no(), "expected a frame count, found '" + std::string(v) + "'");
  if (frames > double(kMaxFrames) ||
      (clip.channel_count > 0 && frames * clip.channel_count > double(kMaxValues)))
    throw BvhError(r.path(), r.line_start(), r.line_no(), "absurd frame count " + std::string(v));
  clip.frame_count = int(frames);
  next_nonblank("'Frame Time: seconds'");
  v = after_label(line, "Frame Time:");
  if (v.empty()) throw BvhError(r.path(), r.line_start(), r.line_no(), "expected 'Frame Time: seconds'");
  if (!Tokenizer::parse(v, clip.frame_time_s) || !(clip.frame_time_s > 0 && clip.frame_time_s <= 10))
    throw BvhError(r.path(), r.line_start(), r.line_no(),
                   "expected a frame time in (0, 10] s, found '" + std::string(v) + "'");
  // Grow with the data actually present rather than trusting the header for the allocation.
  clip.values.reserve(std::min<std::size_t>(std::size_t(clip.frame_count) * clip.channel_count, 1 << 20));
  int f = 0;
  while (r.next(line)) {
    if (blank(line)) continue;
    if (f == clip.frame_count)
      throw BvhError(r.path(), r.line_start(), r.line_no(),
                     "more frame lines than 'Frames: " + std::to_string(clip.frame_count) + "'");
    std::string_view s(line);
    int n = 0;
    std::size_t i = 0;
    while (i < s.size()) {
      while (i < s.size() && is_space(s[i])) ++i;
      if (i == s.size()) break;
      std::size_t e = i;
      while (e < s.size() && !is_space(s[e])) ++e;
      double x;
      std::string_view tok = s.substr(i, e - i);
      if (n == clip.channel_count)
        throw BvhError(r.path(), r.line_start() + i, r.line_no(),
                       "frame " + std::to_string(f + 1) + ": more than the " + std::to_string(clip.channel_count) +
                           " values the HIERARCHY declares");
      if (!Tokenizer::parse(tok, x))
        throw BvhError(r.path(), r.line_start() + i, r.line_no(), "expected a number, found '" + std::string(tok) + "'");
      if (!(std::fabs(x) <= kMaxAbsValue))
        throw BvhError(r.path(), r.line_start() + i, r.line_no(), "absurd value " + std::string(tok));
      clip.values.push_back(x);
      ++n;
      i = e;
    }
    if (n != clip.channel_count)
      throw BvhError(r.path(), r.line_start(), r.line_no(),
                     "frame " + std::to_string(f + 1) + ": expected " + std::to_string(clip.channel_count) +
                         " values, found " + std::to_string(n));
    ++f;
  }
  if (f != clip.frame_count)
    throw BvhError(r.path(), r.line_start(), r.line_no(),
                   "truncated: 'Frames: " + std::to_string(clip.frame_count) + "' but " + std::to_string(f) +
                       " frame lines");
}

}  // namespace

BvhClip read_bvh(const std::string& path) {
  LineReader r(path);
  Tokenizer tk(r);
  BvhClip clip;
  clip.path = path;
  parse_hierarchy(tk, clip);
  if (clip.channel_count == 0) throw BvhError(path, 0, 1, "the HIERARCHY declares no CHANNELS");
  if (!tk.line_done()) {
    Token t = tk.expect_any("end of line");
    tk.fail(t, "expected 'MOTION' on its own line after the hierarchy, found '" + std::string(t.text) + "'");
  }
  Token m = tk.expect_any("MOTION");
  if (m.text == "ROOT") tk.fail(m, "a second ROOT: only one skeleton per file is supported");
  if (m.text != "MOTION") tk.fail(m, "expected 'MOTION', found '" + std::string(m.text) + "'");
  if (!tk.line_done()) {
    Token t = tk.expect_any("end of line");
    tk.fail(t, "expected a new line after 'MOTION', found '" + std::string(t.text) + "'");
  }
  parse_motion(r, clip);
  return clip;
}

Eigen::Quaterniond bvh_local_rotation(const BvhClip& clip, int joint, int frame) {
  const BvhJoint& j = clip.joints[joint];
  const double* v = clip.frame(frame) + j.first_channel;
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  constexpr double kDeg = 3.14159265358979323846 / 180.0;
  for (std::size_t k = 0; k < j.channels.size(); ++k) {
    switch (j.channels[k]) {
      case BvhChannel::Xrotation: q = q * Eigen::AngleAxisd(v[k] * kDeg, Eigen::Vector3d::UnitX()); break;
      case BvhChannel::Yrotation: q = q * Eigen::AngleAxisd(v[k] * kDeg, Eigen::Vector3d::UnitY()); break;
      case BvhChannel::Zrotation: q = q * Eigen::AngleAxisd(v[k] * kDeg, Eigen::Vector3d::UnitZ()); break;
      default: break;
    }
  }
  return q;
}

Eigen::Vector3d bvh_local_translation(const BvhClip& clip, int joint, int frame) {
  const BvhJoint& j = clip.joints[joint];
  const double* v = clip.frame(frame) + j.first_channel;
  Eigen::Vector3d t = j.offset;
  for (std::size_t k = 0; k < j.channels.size(); ++k) {
    switch (j.channels[k]) {
      case BvhChannel::Xposition: t.x() += v[k]; break;
      case BvhChannel::Yposition: t.y() += v[k]; break;
      case BvhChannel::Zposition: t.z() += v[k]; break;
      default: break;
    }
  }
  return t;
}

void bvh_forward_kinematics(const BvhClip& clip, const Eigen::Quaterniond* local_rot,
                            const Eigen::Vector3d* local_trans, Eigen::Vector3d* global_pos,
                            Eigen::Quaterniond* global_rot) {
  for (std::size_t i = 0; i < clip.joints.size(); ++i) {
    const int p = clip.joints[i].parent;
    if (p < 0) {
      global_pos[i] = local_trans[i];
      global_rot[i] = local_rot[i];
    } else {
      global_pos[i] = global_pos[p] + global_rot[p] * local_trans[i];
      global_rot[i] = global_rot[p] * local_rot[i];
    }
  }
}

void bvh_frame_pose(const BvhClip& clip, int frame, std::vector<Eigen::Vector3d>& global_pos,
                    std::vector<Eigen::Quaterniond>& global_rot) {
  const std::size_t n = clip.joints.size();
  std::vector<Eigen::Quaterniond> lr(n);
  std::vector<Eigen::Vector3d> lt(n);
  for (std::size_t i = 0; i < n; ++i) {
    lr[i] = bvh_local_rotation(clip, int(i), frame);
    lt[i] = bvh_local_translation(clip, int(i), frame);
  }
  global_pos.resize(n);
  global_rot.resize(n);
  bvh_forward_kinematics(clip, lr.data(), lt.data(), global_pos.data(), global_rot.data());
}

std::vector<Eigen::Vector3d> bvh_rest_positions(const BvhClip& clip) {
  std::vector<Eigen::Vector3d> p(clip.joints.size());
  for (std::size_t i = 0; i < clip.joints.size(); ++i) {
    const int par = clip.joints[i].parent;
    p[i] = (par < 0 ? Eigen::Vector3d::Zero() : p[par]) + clip.joints[i].offset;
  }
  return p;
}

}  // namespace yelan::camera::sim
