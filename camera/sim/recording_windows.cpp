#include "camera/sim/recording_windows.h"

#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <optional>
#include <stdexcept>

#include "camera/io/event_reader.h"
#include "camera/io/h5_chunks.h"
#include "camera/sim/rng.h"

namespace yelan::camera::sim {

namespace {
[[noreturn]] void fail(const std::string& path, const std::string& what) { recording_error(path, what); }
}  // namespace

struct RecordingWindowStream::Open {
  h5::H5Id file, masks;  // opened once: the info and the masks come from it
  RecordingInfo info;
  std::unique_ptr<EventReader> reader;
  ToreVolume tore;
  std::vector<float> counts;
  std::vector<Event> buf;
  std::optional<h5::RawChunkReader> mask_chunks;  // where each mask is one stored chunk of bytes
  std::size_t first_mask = 0;  // the first mask time with warmup_s of events before it
  std::size_t index = 0;

  Open(const std::string& path, const WindowStreamOptions& o)
      : file(open_recording(path)), info(read_recording_info(file.get(), path)), tore(info.camera.width, info.camera.height, o.tore) {
    reader = open_event_file(info.path);
    if (reader->info().width != info.camera.width || reader->info().height != info.camera.height)
      fail(info.path, "the events are " + std::to_string(reader->info().width) + "x" + std::to_string(reader->info().height) +
                          ", the camera " + std::to_string(info.camera.width) + "x" + std::to_string(info.camera.height));
    const auto t0 = reader->peek_time();
    if (!t0) fail(info.path, "no events");
    info.first_event_us = *t0;
    masks = h5::check(H5Dopen2(file.get(), "masks/data", H5P_DEFAULT), info.path + ": open masks/data");
    const auto dims = h5::shape(masks.get());
    if (dims.size() != 3 || dims[0] != info.mask_t.size() || dims[1] != hsize_t(info.camera.height) ||
        dims[2] != hsize_t(info.camera.width))
      fail(info.path, "masks/data is not (masks/t rows) x height x width");
    if (h5::RawChunkReader::suits(masks.get())) {
      h5::H5Id type = h5::check(H5Dget_type(masks.get()), info.path + ": masks/data type");
      h5::RawChunkReader r(masks.get());
      if (r.element_bytes() == 1 && H5Tget_class(type.get()) == H5T_INTEGER && H5Tget_sign(type.get()) == H5T_SGN_NONE &&
          r.chunk() == std::vector<hsize_t>{1, dims[1], dims[2]})
        mask_chunks.emplace(std::move(r));
    }
    const std::int64_t dt = std::llround(1e6 / o.frame_hz);
    const std::int64_t spacing = info.mask_t[1] - info.mask_t[0];
    if (std::llabs(spacing - dt) > 2)
      fail(info.path, "masks every " + std::to_string(spacing) + " us, the frames are every " + std::to_string(dt) +
                          " us (record at the frame rate: yelan sim writes masks at 50 per second)");
    const std::int64_t warm = std::llround(o.warmup_s * 1e6);
    while (first_mask < info.mask_t.size() && info.mask_t[first_mask] - warm < info.first_event_us) ++first_mask;
    if (o.counts) counts.assign(std::size_t(2) * info.camera.width * info.camera.height, 0.f);
  }

  int windows(int S) const {
    return first_mask + std::size_t(S) <= info.mask_t.size() ? int((info.mask_t.size() - first_mask) / std::size_t(S)) : 0;
  }

  // Feeds the events with t <= T.
  void feed(std::int64_t T) {
    constexpr std::size_t kBatch = 1 << 16;
    std::size_t n;
    do {
      buf.clear();
      n = reader->read_until(buf, T + 1, kBatch);
      tore.update(buf);
      if (!counts.empty()) {
        const std::size_t plane = counts.size() / 2;
        for (const Event& e : buf)
          if (e.x < info.camera.width && e.y < info.camera.height)
            counts[(e.p ? 0 : plane) + std::size_t(e.y) * info.camera.width + e.x] += 1.f;
      }
    } while (n == kBatch);
  }

  void read_mask(std::size_t m, std::vector<std::uint8_t>& out) {
    const hsize_t start[3] = {hsize_t(m), 0, 0};
    try {
      if (mask_chunks && mask_chunks->read(masks.get(), start, out)) return;
    } catch (const h5::H5Failure& e) {
      throw h5::H5Failure(info.path + ": read mask " + std::to_string(m) + ": " + e.what());
    }
    out.resize(std::size_t(info.camera.width) * info.camera.height);
    const hsize_t count[3] = {1, hsize_t(info.camera.height), hsize_t(info.camera.width)};
    h5::H5Id fspace = h5::check(H5Dget_space(masks.get()), "dataspace");
    h5::check(H5Sselect_hyperslab(fspace.get(), H5S_SELECT_SET, start, nullptr, count, nullptr), "select mask");
    h5::H5Id mspace = h5::check(H5Screate_simple(3, count, nullptr), "dataspace");
    h5::check(H5Dread(masks.get(), H5T_NATIVE_UINT8, mspace.get(), fspace.get(), H5P_DEFAULT, out.data()),
              info.path + ": read mask " + std::to_string(m));
  }

};

RecordingWindowStream::RecordingWindowStream(std::vector<std::string> paths, std::uint64_t seed, WindowStreamOptions options)
    : paths_(std::move(paths)), seed_(seed), opt_(options) {
  if (paths_.empty()) throw std::invalid_argument("recording stream: no recordings");
  if (opt_.window < 1 || !(opt_.frame_hz > 0) || !(opt_.warmup_s >= 0) || opt_.cursors < 1 || opt_.windows_per_visit < 1)
    throw std::invalid_argument("recording stream: need window >= 1, frame rate > 0, warm-up >= 0, cursors and windows per visit >= 1");
}

RecordingWindowStream::~RecordingWindowStream() = default;

RecordingWindowStream::Open& RecordingWindowStream::open(std::size_t i) {
  if (!open_ || open_->index != i) {
    open_.reset();  // one file open at a time
    open_ = std::make_unique<Open>(paths_[i], opt_);
    open_->index = i;
  }
  return *open_;
}

const RecordingInfo& RecordingWindowStream::info(std::size_t i) { return open(i).info; }
int RecordingWindowStream::windows_in(std::size_t i) { return open(i).windows(opt_.window); }

void RecordingWindowStream::fill(Open& r, std::size_t first, bool fresh, SimWindow& out) {
  const std::int64_t dt = std::llround(1e6 / opt_.frame_hz);
  out.scene = r.info.name;
  out.seed = 0;
  out.camera = r.info.camera;
  out.frames.resize(std::size_t(opt_.window));
  if (fresh) {
    r.tore.reset();
    const double history = std::max(opt_.warmup_s, opt_.history_s);
    r.reader->seek(std::max<std::int64_t>(r.info.first_event_us, r.info.mask_t[first] - std::llround(history * 1e6)));
    if (!r.counts.empty()) {
      r.feed(r.info.mask_t[first] - dt);
      std::fill(r.counts.begin(), r.counts.end(), 0.f);
    }
  }
  for (int k = 0; k < opt_.window; ++k) {
    SimFrame& f = out.frames[std::size_t(k)];
    const std::size_t m = first + std::size_t(k);
    f.t_us = r.info.mask_t[m];
    // A label-only frame needs no events: the next read-out feeds up to its own time (the
    // TORE's state after the same events is the same however they were fed).
    if (opt_.tore_frames > 0 && k >= opt_.tore_frames && r.counts.empty()) {
      f.tore.clear();
    } else {
      r.feed(f.t_us);
      f.tore.resize(r.tore.volume_size());
      r.tore.readout(f.t_us, f.tore.data());
    }
    r.read_mask(m, f.mask);
    if (!r.counts.empty()) {
      f.counts = r.counts;
      std::fill(r.counts.begin(), r.counts.end(), 0.f);
    } else {
      f.counts.clear();
    }
    label_at(r.info, f.t_us, f.joints_mm, f.valid);
  }
}

RecordingWindowStream::Planned RecordingWindowStream::plan_from_cursor() {
  const std::size_t S = std::size_t(opt_.window);
  const std::uint64_t B = std::uint64_t(opt_.cursors), M = std::uint64_t(opt_.windows_per_visit);
  const std::uint64_t b = k_ % B, step = k_ / B, visit = step / M, j = step % M;
  if (cursors_.size() != B) cursors_.resize(B);
  Cursor& c = cursors_[b];
  if (!c.open || c.visit != visit) {
    c.open.reset();
    c.open = std::make_unique<Open>(paths_[hash64(seed_, 0xc0250 + b, visit) % paths_.size()], opt_);
    c.visit = visit;
    c.end = 0;
  }
  Open& r = *c.open;
  const std::size_t frames = r.info.mask_t.size() - std::min(r.info.mask_t.size(), r.first_mask);
  if (frames < S)
    fail(r.info.path, "too short for a window of " + std::to_string(S) + " frames after " + std::to_string(opt_.warmup_s) +
                          " s of warm-up");
  // M slots side by side, one window inside each: increasing times, never overlapping (a
  // recording too short for M slots gives overlapping picks, each read afresh).
  const std::size_t slot = frames / M;
  Planned p{&r, 0, true};
  if (slot >= S) {
    p.first = r.first_mask + j * slot + hash64(seed_, 0x5107 + b, visit * M + j) % (slot - S + 1);
    p.fresh = p.first < c.end;  // behind the reader: seek back
  } else {
    p.first = r.first_mask + hash64(seed_, 0x5107 + b, visit * M + j) % (frames - S + 1);
  }
  c.end = p.first + S;
  ++k_;
  return p;
}

void RecordingWindowStream::read_planned(const Planned& p, SimWindow& out) {
  Open& r = *p.open;
  // Read on from the last window: the TORE then equals a fresh one started history_s before
  // (events older than TORE's tau read 0 either way), so a resumed run is bit-exact.
  if (!p.fresh && !r.counts.empty()) {
    r.feed(r.info.mask_t[p.first] - std::llround(1e6 / opt_.frame_hz));
    std::fill(r.counts.begin(), r.counts.end(), 0.f);
  }
  fill(r, p.first, p.fresh, out);
}

void RecordingWindowStream::next_batch(std::span<SimWindow> out, int threads) {
  if (!cursor_mode() || opt_.cursors == 1 || threads <= 1) {
    for (SimWindow& w : out) next(w);
    return;
  }
  // Consecutive windows come from consecutive cursors: any `cursors` of them from distinct ones.
  const std::size_t group = std::size_t(opt_.cursors);
  std::vector<Planned> plans;
  std::vector<std::exception_ptr> errors;
  for (std::size_t g = 0; g < out.size(); g += group) {
    const std::size_t n = std::min(group, out.size() - g);
    plans.clear();
    for (std::size_t i = 0; i < n; ++i) plans.push_back(plan_from_cursor());
    errors.assign(n, nullptr);
#pragma omp parallel for schedule(dynamic, 1) num_threads(std::min<int>(threads, int(n)))
    for (std::size_t i = 0; i < n; ++i) {
      try {
        read_planned(plans[i], out[g + i]);
      } catch (...) {
        errors[i] = std::current_exception();
      }
    }
    for (const auto& e : errors)
      if (e) std::rethrow_exception(e);
  }
}

void RecordingWindowStream::next(SimWindow& out) {
  const std::size_t S = std::size_t(opt_.window);
  if (cursor_mode()) {
    read_planned(plan_from_cursor(), out);
    return;
  }
  if (opt_.shuffle) {
    const std::size_t i = opt_.spread ? k_ % paths_.size() : hash64(seed_, 0x5c3e, k_) % paths_.size();
    Open& r = open(i);
    const int fits = int(r.info.mask_t.size()) - int(r.first_mask) - int(S) + 1;
    if (fits < 1)
      fail(r.info.path, "too short for a window of " + std::to_string(S) + " frames after " +
                            std::to_string(opt_.warmup_s) + " s of warm-up");
    const std::size_t first = r.first_mask + hash64(seed_, 0x5717, k_) % std::size_t(fits);
    ++k_;
    fill(r, first, true, out);
    return;
  }
  bool fresh = false;
  if (!seq_started_ || seq_mask_ + S > open(seq_rec_).info.mask_t.size()) {
    std::size_t tried = 0;
    do {
      if (seq_started_) seq_rec_ = (seq_rec_ + 1) % paths_.size();
      seq_started_ = true;
      if (++tried > paths_.size()) fail(paths_[0], "no recording holds a window of " + std::to_string(S) + " frames");
    } while (windows_in(seq_rec_) == 0);
    seq_mask_ = open(seq_rec_).first_mask;
    fresh = true;
  }
  Open& r = open(seq_rec_);
  fill(r, seq_mask_, fresh, out);
  seq_mask_ += S;
  ++k_;
}

void RecordingWindowStream::seek_window(std::uint64_t k) {
  if (opt_.shuffle) {
    k_ = k;
    cursors_.clear();  // reopened on demand: reading on from a file's start equals a seek
    return;
  }
  seq_started_ = false;
  seq_rec_ = 0;
  open_.reset();
  k_ = 0;
  SimWindow skip;
  for (std::uint64_t i = 0; i < k; ++i) next(skip);
}

}  // namespace yelan::camera::sim
