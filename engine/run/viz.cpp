#include "engine/run/viz.h"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <stdexcept>

#include "camera/io/temp_file.h"
#include "camera/repr/preview_png.h"
#include "camera/sim/preview.h"
#include "engine/subprocess.h"

namespace yelan::run {

namespace {

bool is_video(const std::string& target) {
  if (target.size() < 4) return false;
  std::string ext = target.substr(target.size() - 4);
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  return ext == ".mp4";
}

}  // namespace


bool RunViz::have_ffmpeg() { return on_path("ffmpeg"); }

void RunViz::check_target(const std::string& target) {
  if (is_video(target) && !have_ffmpeg())
    throw std::invalid_argument("--viz " + target + ": a video needs ffmpeg on PATH (apt-get install ffmpeg); "
                                "give a directory for PNG frames instead");
}

RunViz::RunViz(const std::string& target, int w, int h, int every, double fps)
    : w_(w), h_(h), every_(std::max(1, every)), fps_(fps > 0 ? fps / std::max(1, every) : 25) {
  check_target(target);
  if (is_video(target)) {
    video_ = target;
    dir_ = target + ".frames";
  } else {
    dir_ = target;
  }
  std::filesystem::create_directories(dir_);
}

namespace {

// A 5x7 bitmap font for the verdict line ("PERSON 0.97", "NO PERSON 0.03"): rows top down,
// bit 4 the leftmost pixel.
struct Glyph {
  char c;
  std::uint8_t rows[7];
};
constexpr Glyph kFont[] = {
    {'N', {17, 25, 21, 19, 17, 17, 17}}, {'O', {14, 17, 17, 17, 17, 17, 14}}, {'P', {30, 17, 17, 30, 16, 16, 16}},
    {'E', {31, 16, 16, 30, 16, 16, 31}}, {'R', {30, 17, 17, 30, 20, 18, 17}}, {'S', {15, 16, 16, 14, 1, 1, 30}},
    {'0', {14, 17, 19, 21, 25, 17, 14}}, {'1', {4, 12, 4, 4, 4, 4, 14}},     {'2', {14, 17, 1, 2, 4, 8, 31}},
    {'3', {30, 1, 1, 14, 1, 1, 30}},     {'4', {2, 6, 10, 18, 31, 2, 2}},     {'5', {31, 16, 30, 1, 1, 17, 14}},
    {'6', {6, 8, 16, 30, 17, 17, 14}},   {'7', {31, 1, 2, 4, 8, 8, 8}},       {'8', {14, 17, 17, 14, 17, 17, 14}},
    {'9', {14, 17, 17, 15, 1, 2, 12}},   {'.', {0, 0, 0, 0, 0, 12, 12}},
};

// `text` at (x0, y0), each font pixel `scale` x `scale`, in `rgb`; characters not in the
// font are spaces.
void draw_text(std::vector<std::uint8_t>& img, int w, int h, int x0, int y0, const std::string& text, int scale,
               const std::uint8_t rgb[3]) {
  for (std::size_t k = 0; k < text.size(); ++k) {
    const Glyph* g = nullptr;
    for (const Glyph& f : kFont)
      if (f.c == text[k]) g = &f;
    if (!g) continue;
    for (int r = 0; r < 7; ++r)
      for (int c = 0; c < 5; ++c) {
        if (!(g->rows[r] >> (4 - c) & 1)) continue;
        for (int dy = 0; dy < scale; ++dy)
          for (int dx = 0; dx < scale; ++dx) {
            const int x = x0 + (int(k) * 6 + c) * scale + dx, y = y0 + r * scale + dy;
            if (x < 0 || y < 0 || x >= w || y >= h) continue;
            std::copy_n(rgb, 3, &img[(std::size_t(y) * w + x) * 3]);
          }
      }
  }
}

}  // namespace

void RunViz::add(const Pose& p, const PosePipeline& pipe) {
  if (seen_++ % every_) return;
  const int W = 3 * w_;
  std::vector<std::uint8_t> rgb(std::size_t(W) * h_ * 3, 0), panel(std::size_t(w_) * h_ * 3, 0);
  const std::vector<float>& tore = pipe.last_tore();
  const std::vector<float>& mask = pipe.last_stage1_mask();
  const int d = pipe.mask_downscale(), mw = w_ / d, mh = h_ / d;
  const std::size_t plane = std::size_t(w_) * h_;
  for (int y = 0; y < h_; ++y)
    for (int x = 0; x < w_; ++x) {
      const std::size_t i = std::size_t(y) * w_ + x;
      const float on = tore.size() >= 6 * plane ? tore[i] : 0.f, off = tore.size() >= 6 * plane ? tore[3 * plane + i] : 0.f;
      const bool m = !mask.empty() && x / d < mw && y / d < mh && mask[std::size_t(y / d) * mw + x / d] > 0;
      std::uint8_t* q = &panel[i * 3];
      q[0] = std::uint8_t(std::lround(255 * on));
      q[1] = m ? 60 : 0;
      q[2] = std::uint8_t(std::lround(255 * off));
    }
  camera::sim::CameraModel cam;
  cam.width = w_, cam.height = h_, cam.fx = cam.fy = pipe.focal_px(), cam.cx = w_ / 2.0, cam.cy = h_ / 2.0;
  camera::sim::Label l;
  for (int j = 0; j < 13; ++j) l.joints_mm[j] = {p.joints_mm[j][0], p.joints_mm[j][1], p.joints_mm[j][2]};
  std::vector<std::uint8_t> skel = panel;
  if (p.person) camera::sim::draw_skeleton(skel, w_, h_, cam, l);
  char verdict[32];
  std::snprintf(verdict, sizeof verdict, "%s %.2f", p.person ? "PERSON" : "NO PERSON", double(p.confidence));
  static constexpr std::uint8_t kYes[3] = {120, 255, 120}, kNo[3] = {255, 200, 60};
  draw_text(skel, w_, h_, 4, 4, verdict, 2, p.person ? kYes : kNo);
  // Side view: depth (z) across, height (y) down, centred on the hips, 10 mm per pixel.
  std::vector<std::uint8_t> side(std::size_t(w_) * h_ * 3, 24);
  camera::sim::Label s = l;
  const double zc = (p.joints_mm[5][2] + p.joints_mm[6][2]) / 2, yc = (p.joints_mm[5][1] + p.joints_mm[6][1]) / 2;
  for (int j = 0; j < 13; ++j) s.joints_mm[j] = {(p.joints_mm[j][2] - zc) / 5.0, (p.joints_mm[j][1] - yc) / 5.0, 2.0};
  camera::sim::CameraModel ortho = cam;
  ortho.fx = ortho.fy = 1;  // with z = 2 above: 1 px per 10 mm
  if (p.person) camera::sim::draw_skeleton(side, w_, h_, ortho, s);
  for (int y = 0; y < h_; ++y) {
    std::copy_n(&panel[std::size_t(y) * w_ * 3], w_ * 3, &rgb[std::size_t(y) * W * 3]);
    std::copy_n(&skel[std::size_t(y) * w_ * 3], w_ * 3, &rgb[(std::size_t(y) * W + w_) * 3]);
    std::copy_n(&side[std::size_t(y) * w_ * 3], w_ * 3, &rgb[(std::size_t(y) * W + 2 * w_) * 3]);
  }
  char name[64];
  std::snprintf(name, sizeof name, "pose_%06d.png", written_);
  camera::write_png_rgb((std::filesystem::path(dir_) / name).string(), W, h_, rgb);
  ++written_;
}

void RunViz::finish() {
  const bool video = !video_.empty();
  if (written_ == 0 || (!video && !have_ffmpeg())) return;
  const std::string out = video ? video_ : (std::filesystem::path(dir_) / "run.mp4").string();
  // ffmpeg overwrites (-y) a temporary file that is ours, created exclusively under a random
  // name (a link planted at a predictable name would be followed); "-f mp4" names the muxer.
  std::unique_ptr<camera::TempFile> part;
  try {
    part = std::make_unique<camera::TempFile>(out);
  } catch (const std::runtime_error& e) {
    problem_ = e.what();
    return;
  }
  char rate[32];
  std::snprintf(rate, sizeof rate, "%.3f", fps_);
  // ffmpeg reads the input as a frame-number pattern (a literal '%' in the folder is "%%"),
  // and "file:" keeps a ':' or a leading '-' in a path from reading as a protocol or option.
  std::string pattern;
  for (char c : dir_) pattern += c == '%' ? std::string("%%") : std::string(1, c);
  pattern += "/pose_%06d.png";
  Program ffmpeg({"ffmpeg", "-loglevel", "error", "-nostdin", "-y", "-framerate", rate, "-f", "image2", "-i",
                  "file:" + pattern, "-pix_fmt", "yuv420p", "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-f", "mp4",
                  "file:" + part->path()});
  ffmpeg.show_stderr = true;  // its own reason, when it fails
  if (const ProgramResult r = run_program(ffmpeg); !r.ok()) {
    problem_ = "ffmpeg could not make " + out + " (" + r.why() + ")";
    return;  // the temporary file goes with `part`
  }
  try {
    part->commit();
  } catch (const std::runtime_error& e) {
    problem_ = e.what();
    return;
  }
  encoded_ = true;
  std::error_code ec;
  if (video) std::filesystem::remove_all(dir_, ec);
}

std::string RunViz::summary() const {
  const std::string n = std::to_string(written_);
  if (!video_.empty() && encoded_) return n + " frames in " + video_;
  const std::string pictures = n + " pictures " + (problem_.empty() ? "in " : "kept in ") + dir_;
  if (!problem_.empty()) return problem_ + ": " + pictures;
  return pictures + (encoded_ ? " (and " + (std::filesystem::path(dir_) / "run.mp4").string() + ")" : "");
}

}  // namespace yelan::run
