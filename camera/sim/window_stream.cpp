#include "camera/sim/window_stream.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "camera/sim/rng.h"

namespace yelan::camera::sim {

// Keeps the TORE up to date per event and the latest rendered mask.
struct SimWindowStream::Sink final : SimSink {
  ToreVolume tore;
  std::vector<std::uint8_t> last_mask;
  std::int64_t mask_t = -1;
  std::vector<float> counts;  // 2 x H x W when counting, else empty
  bool counting_from_frame = false;  // the warm-up's events are out of the first count
  int width;
  Sink(int w, int h, ToreOptions o, bool count) : tore(w, h, o), width(w) {
    if (count) counts.assign(std::size_t(2) * w * h, 0.f);
  }
  void events(std::span<const Event> ev) override {
    tore.update(ev);
    if (counts.empty()) return;
    const std::size_t plane = counts.size() / 2;
    for (const Event& e : ev) counts[(e.p ? 0 : plane) + std::size_t(e.y) * width + e.x] += 1.f;
  }
  void mask(std::int64_t t_us, const RenderedFrame& f) override {
    mask_t = t_us;
    last_mask.assign(f.mask.begin(), f.mask.end());
  }
};

SimWindowStream::SimWindowStream(std::vector<SimSpec> scenes, std::uint64_t seed, WindowStreamOptions options)
    : scenes_(std::move(scenes)), seed_(seed), opt_(options) {
  if (scenes_.empty()) throw std::invalid_argument("simulator stream: no scenes");
  if (opt_.window < 1 || !(opt_.frame_hz > 0) || !(opt_.warmup_s >= 0))
    throw std::invalid_argument("simulator stream: need window >= 1, frame rate > 0, warm-up >= 0");
  if (opt_.scene_s < opt_.warmup_s + opt_.window / opt_.frame_hz)
    throw std::invalid_argument("simulator stream: a scene must last at least the warm-up plus one window");
}

SimWindowStream::~SimWindowStream() = default;

void SimWindowStream::start_scene() {
  const std::uint64_t pick = opt_.shuffle ? hash64(seed_, 0x5c3e, started_) : started_;
  SimSpec spec = scenes_[pick % scenes_.size()];
  spec.seed = hash64(seed_, 0x5717, started_) & 0xffffffffffffull;
  spec.duration_s = opt_.scene_s;
  // Masks exactly at the frame times; the warm-up is a whole number of frames.
  spec.mask_hz = opt_.frame_hz;
  ++started_;
  sim_ = std::make_unique<Simulator>(spec);
  sink_ = std::make_unique<Sink>(sim_->camera().width, sim_->camera().height, opt_.tore, opt_.counts);
  frame_index_ = std::llround(std::ceil(opt_.warmup_s * opt_.frame_hz));
}

void SimWindowStream::next(SimWindow& out) {
  const double dt = 1.0 / opt_.frame_hz;
  if (!sim_ || (frame_index_ + opt_.window) * dt > opt_.scene_s + 1e-9) start_scene();
  out.scene = sim_->spec().name;
  out.seed = sim_->spec().seed;
  out.camera = sim_->camera();
  out.frames.resize(std::size_t(opt_.window));
  for (SimFrame& f : out.frames) {
    const double t = double(frame_index_) * dt;
    if (opt_.counts && !sink_->counting_from_frame) {
      sim_->run_until(std::max(0.0, t - dt), *sink_);
      std::fill(sink_->counts.begin(), sink_->counts.end(), 0.f);
      sink_->counting_from_frame = true;
    }
    sim_->run_until(t, *sink_);
    f.t_us = std::llround(t * 1e6);
    if (sink_->mask_t != f.t_us) throw std::logic_error("simulator stream: no mask rendered at the frame time");
    f.tore.resize(sink_->tore.volume_size());
    sink_->tore.readout(f.t_us, f.tore.data());
    f.mask = sink_->last_mask;
    if (opt_.counts) {
      f.counts = sink_->counts;
      std::fill(sink_->counts.begin(), sink_->counts.end(), 0.f);
    } else {
      f.counts.clear();
    }
    const Label l = sim_->label_at(t);
    f.joints_mm = l.joints_mm;
    f.valid = l.valid;
    ++frame_index_;
  }
}

}  // namespace yelan::camera::sim
