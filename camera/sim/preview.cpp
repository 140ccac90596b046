#include "camera/sim/preview.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "camera/repr/preview_png.h"

namespace yelan::camera::sim {

namespace {

// SPEC's skeleton edges over the DHP19 order (head 0, shoulders 1/2, elbows 3/4, hips 5/6,
// hands 7/8, knees 9/10, feet 11/12).
constexpr int kEdges[][2] = {{0, 1}, {0, 2}, {1, 3}, {3, 7}, {2, 4}, {4, 8}, {1, 5},  {5, 9},
                             {9, 11}, {2, 6}, {6, 10}, {10, 12}, {1, 2}, {5, 6}};

void put(std::vector<std::uint8_t>& rgb, int w, int h, int x, int y, std::uint8_t r, std::uint8_t g, std::uint8_t b) {
  if (x < 0 || y < 0 || x >= w || y >= h) return;
  std::uint8_t* p = &rgb[(std::size_t(y) * w + x) * 3];
  p[0] = r, p[1] = g, p[2] = b;
}

std::uint8_t display(float intensity, double level) {
  const double v = std::pow(std::clamp(double(intensity) / level, 0.0, 1.0), 1 / 2.2);
  return std::uint8_t(std::lround(255 * v));
}

}  // namespace

void draw_skeleton(std::vector<std::uint8_t>& rgb, int w, int h, const CameraModel& cam, const Label& l) {
  auto project = [&](int j, double& u, double& v) {
    const Vec3& c = l.joints_mm[j];
    if (c.z() <= 1) return false;
    u = cam.fx * c.x() / c.z() + cam.cx, v = cam.fy * c.y() / c.z() + cam.cy;
    return true;
  };
  for (auto [a, b] : kEdges) {
    double ua, va, ub, vb;
    if (!project(a, ua, va) || !project(b, ub, vb)) continue;
    const int n = int(std::ceil(std::max(std::abs(ub - ua), std::abs(vb - va)))) + 1;
    if (n > 4 * (w + h)) continue;
    for (int i = 0; i <= n; ++i) {
      const double s = double(i) / n;
      put(rgb, w, h, int(std::floor(ua + s * (ub - ua))), int(std::floor(va + s * (vb - va))), 60, 230, 60);
    }
  }
  for (int j = 0; j < kJointCount; ++j) {
    double u, v;
    if (!project(j, u, v)) continue;
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) put(rgb, w, h, int(std::floor(u)) + dx, int(std::floor(v)) + dy, 255, 230, 40);
  }
}

PreviewSink::PreviewSink(const std::string& dir, const Simulator& sim, int every, SimSink* next)
    : dir_(dir), sim_(sim), every_(std::max(1, every)), next_(next), w_(sim.camera().width), h_(sim.camera().height) {
  std::filesystem::create_directories(dir_);
  on_.assign(std::size_t(w_) * h_, 0);
  off_.assign(std::size_t(w_) * h_, 0);
}

void PreviewSink::events(std::span<const Event> ev) {
  for (const Event& e : ev)
    if (e.x < w_ && e.y < h_) {
      auto& c = (e.p ? on_ : off_)[std::size_t(e.y) * w_ + e.x];
      if (c < 65535) ++c;
    }
  if (next_) next_->events(ev);
}

void PreviewSink::label(const Label& l) {
  if (next_) next_->label(l);
}

void PreviewSink::mask(std::int64_t t_us, const RenderedFrame& f) {
  if (next_) next_->mask(t_us, f);
  if (ticks_++ % every_ == 0 && t_us > 0) {
    const CameraModel& cam = sim_.camera();
    const Label l = sim_.label_at(double(t_us) * 1e-6);
    const double level = lighting(sim_.spec().scene.light, false).level;
    const int W = 3 * w_;
    std::vector<std::uint8_t> rgb(std::size_t(W) * h_ * 3, 0), events(std::size_t(w_) * h_ * 3, 0);
    for (int y = 0; y < h_; ++y)
      for (int x = 0; x < w_; ++x) {
        const std::size_t i = std::size_t(y) * w_ + x;
        const std::uint8_t g = display(f.intensity[i], level);
        std::uint8_t* p0 = &rgb[(std::size_t(y) * W + x) * 3];
        p0[0] = p0[1] = p0[2] = g;
        std::uint8_t* p1 = &rgb[(std::size_t(y) * W + w_ + x) * 3];
        p1[0] = f.mask[i] ? g / 3 : g / 2, p1[1] = f.mask[i] ? std::uint8_t(std::min(255, g / 3 + 150)) : g / 2,
        p1[2] = f.mask[i] ? g / 3 : g / 2;
        std::uint8_t* e = &events[i * 3];
        if (on_[i] || off_[i]) {
          e[0] = on_[i] >= off_[i] ? 255 : 40;
          e[1] = 40;
          e[2] = off_[i] > on_[i] ? 255 : 40;
        }
      }
    draw_skeleton(events, w_, h_, cam, l);
    for (int y = 0; y < h_; ++y)
      std::copy_n(&events[std::size_t(y) * w_ * 3], w_ * 3, &rgb[(std::size_t(y) * W + 2 * w_) * 3]);
    char name[64];
    std::snprintf(name, sizeof name, "frame_%08lld.png", static_cast<long long>(t_us));
    const std::string path = (std::filesystem::path(dir_) / name).string();
    write_png_rgb(path, W, h_, rgb);
    written_.push_back(path);
    // Keep a spread of panels for the contact sheet in bounded memory: when 24 are kept,
    // drop every other one and keep half as often from then on.
    if ((ticks_ / every_) % keep_stride_ == 0) kept_.push_back({t_us, std::move(events)});
    if (kept_.size() >= 24) {
      std::vector<Panel> half;
      for (std::size_t i = 0; i < kept_.size(); i += 2) half.push_back(std::move(kept_[i]));
      kept_ = std::move(half);
      keep_stride_ *= 2;
    }
  }
  std::fill(on_.begin(), on_.end(), 0);
  std::fill(off_.begin(), off_.end(), 0);
}

std::vector<std::string> PreviewSink::finish() {
  if (!kept_.empty()) {
    const int n = int(std::min<std::size_t>(12, kept_.size())), cols = std::min(4, n), rows = (n + cols - 1) / cols;
    const int W = cols * w_, H = rows * h_;
    std::vector<std::uint8_t> sheet(std::size_t(W) * H * 3, 255);
    for (int k = 0; k < n; ++k) {
      const Panel& p = kept_[std::size_t(k) * kept_.size() / n];
      const int ox = (k % cols) * w_, oy = (k / cols) * h_;
      for (int y = 0; y < h_; ++y)
        std::copy_n(&p.rgb[std::size_t(y) * w_ * 3], w_ * 3, &sheet[(std::size_t(oy + y) * W + ox) * 3]);
      for (int y = 0; y < h_; ++y) put(sheet, W, H, ox + w_ - 1, oy + y, 128, 128, 128);  // panel borders
      for (int x = 0; x < w_; ++x) put(sheet, W, H, ox + x, oy + h_ - 1, 128, 128, 128);
    }
    const std::string path = (std::filesystem::path(dir_) / "contact_sheet.png").string();
    write_png_rgb(path, W, H, sheet);
    written_.push_back(path);
  }
  return written_;
}

}  // namespace yelan::camera::sim
