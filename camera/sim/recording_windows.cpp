#include "camera/sim/recording_windows.h"

#include <hdf5.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <stdexcept>

#include "camera/io/event_reader.h"
#include "camera/io/format_error.h"
#include "camera/io/h5.h"
#include "camera/io/untrusted.h"
#include "camera/sim/rng.h"

namespace yelan::camera::sim {

namespace fs = std::filesystem;

namespace {

constexpr const char* kSuffix = ".yelan.h5";

// A FormatError: a malformed recording is bad input (exit 2), as any other malformed file.
[[noreturn]] void fail(const std::string& path, const std::string& what) {
  throw FormatError(path, 0, what);
}

// Rows of an N x (row dims) dataset, all of them, as mem_type; checks the row shape.
template <class T>
std::vector<T> read_all(hid_t f, const std::string& path, const std::string& name, hid_t mem_type,
                        const std::vector<hsize_t>& row) {
  if (!h5::exists(f, name)) fail(path, "no dataset " + name + " (not a labelled recording from `yelan sim`)");
  h5::H5Id ds = h5::check(H5Dopen2(f, name.c_str(), H5P_DEFAULT), "open " + name);
  const std::vector<hsize_t> dims = h5::shape(ds.get());
  if (dims.size() != row.size() + 1 || !std::equal(row.begin(), row.end(), dims.begin() + 1))
    fail(path, name + " has the wrong shape");
  std::size_t per = 1;
  for (hsize_t d : row) per *= std::size_t(d);
  std::vector<T> out(std::size_t(dims[0]) * per);
  if (!out.empty()) h5::check(H5Dread(ds.get(), mem_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()), "read " + name);
  return out;
}

RecordingInfo read_info(hid_t f, const std::string& path);

// Everything a reader of the recording will touch: labels, cameras, every mask, every event.
void read_whole_recording(const std::string& path) {
  h5::silence_errors();
  const h5::H5Id f = h5::open_file(path);
  const RecordingInfo info = read_info(f.get(), path);
  h5::H5Id masks = h5::check(H5Dopen2(f.get(), "masks/data", H5P_DEFAULT), "open masks/data");
  const auto dims = h5::shape(masks.get());
  if (dims.size() != 3 || dims[1] != hsize_t(info.camera.height) || dims[2] != hsize_t(info.camera.width)) return;
  std::vector<std::uint8_t> one(std::size_t(dims[1]) * dims[2]);
  for (hsize_t m = 0; m < dims[0]; ++m) {
    const hsize_t start[3] = {m, 0, 0}, count[3] = {1, dims[1], dims[2]};
    h5::H5Id fspace = h5::check(H5Dget_space(masks.get()), "dataspace");
    h5::check(H5Sselect_hyperslab(fspace.get(), H5S_SELECT_SET, start, nullptr, count, nullptr), "select mask");
    h5::H5Id mspace = h5::check(H5Screate_simple(3, count, nullptr), "dataspace");
    h5::check(H5Dread(masks.get(), H5T_NATIVE_UINT8, mspace.get(), fspace.get(), H5P_DEFAULT, one.data()), "read mask");
  }
  auto events = open_event_file(path);
  std::vector<Event> v;
  while (events->read(v, 1 << 20)) v.clear();
}

h5::H5Id open_recording(const std::string& path) {
  h5::silence_errors();
  vet_in_child(path, [&] { read_whole_recording(path); });
  try {
    return h5::open_file(path);
  } catch (const std::exception& e) {
    fail(path, std::string("cannot open as HDF5: ") + e.what());
  }
}

// Everything but the events and the mask pictures, from an open file.
RecordingInfo read_info(hid_t f, const std::string& path) {
  RecordingInfo r;
  r.path = path;
  r.name = fs::path(path).filename().string();
  if (r.name.size() > std::string(kSuffix).size() && r.name.ends_with(kSuffix))
    r.name.resize(r.name.size() - std::string(kSuffix).size());
  if (!h5::exists(f, "labels/t") || !h5::exists(f, "masks/t"))
    fail(path, "no labels/t or masks/t: an event file, not a labelled recording (`yelan sim` writes those)");
  try {
    const auto w = h5::read_scalar_i64(f, "camera/width"), h = h5::read_scalar_i64(f, "camera/height");
    if (!w || !h || *w < 1 || *h < 1 || *w > 65536 || *h > 65536) fail(path, "no valid camera/width and camera/height");
    r.camera.width = int(*w);
    r.camera.height = int(*h);
    const auto k = read_all<double>(f, path, "camera/K", H5T_NATIVE_DOUBLE, {3});
    if (k.size() != 9) fail(path, "camera/K is not 3x3");
    r.camera.fx = k[0], r.camera.fy = k[4], r.camera.cx = k[2], r.camera.cy = k[5];
    r.character = h5::read_attr_string(f, "character").value_or("");
    r.motion = h5::read_attr_string(f, "motion").value_or("");
    r.view = h5::read_attr_string(f, "view").value_or("");
    r.lighting = h5::read_attr_string(f, "lighting").value_or("");
    r.background = h5::read_attr_string(f, "background").value_or("");
    if (const auto dancer = h5::read_attr_i64(f, "dancer")) r.dancer = *dancer != 0;
    if (const auto scene = h5::read_attr_string(f, "scene")) {
      const auto j = nlohmann::json::parse(*scene, nullptr, false);
      if (!j.is_discarded() && j.contains("occluders") && j["occluders"].is_boolean()) r.occluded = j["occluders"].get<bool>();
    }
    r.label_t = read_all<std::int64_t>(f, path, "labels/t", H5T_NATIVE_INT64, {});
    r.joints = read_all<float>(f, path, "labels/joints", H5T_NATIVE_FLOAT, {hsize_t(kJointCount), 3});
    r.valid = read_all<std::uint8_t>(f, path, "labels/valid", H5T_NATIVE_UINT8, {hsize_t(kJointCount)});
    r.mask_t = read_all<std::int64_t>(f, path, "masks/t", H5T_NATIVE_INT64, {});
  } catch (const h5::H5Failure& e) {
    fail(path, e.what());
  }
  if (r.joints.size() != r.label_t.size() * kJointCount * 3 || r.valid.size() != r.label_t.size() * kJointCount)
    fail(path, "labels/t, labels/joints and labels/valid differ in length");
  if (r.label_t.empty() || r.mask_t.size() < 2) fail(path, "no labels or fewer than two masks");
  for (std::size_t i = 1; i < r.label_t.size(); ++i)
    if (r.label_t[i] <= r.label_t[i - 1]) fail(path, "labels/t is not increasing at row " + std::to_string(i));
  for (std::size_t i = 1; i < r.mask_t.size(); ++i)
    if (r.mask_t[i] <= r.mask_t[i - 1]) fail(path, "masks/t is not increasing at row " + std::to_string(i));
  return r;
}

}  // namespace

RecordingInfo read_recording_info(const std::string& path) {
  const h5::H5Id file = open_recording(path);
  return read_info(file.get(), path);
}

std::vector<std::uint8_t> read_recording_masks(const std::string& path, std::size_t first, std::size_t n) {
  const h5::H5Id file = open_recording(path);
  try {
    h5::H5Id masks = h5::check(H5Dopen2(file.get(), "masks/data", H5P_DEFAULT), "open masks/data");
    const auto dims = h5::shape(masks.get());
    if (dims.size() != 3) fail(path, "masks/data is not masks x height x width");
    if (first >= dims[0]) return {};
    n = std::min<std::size_t>(n, std::size_t(dims[0]) - first);
    std::vector<std::uint8_t> out(n * std::size_t(dims[1]) * dims[2]);
    const hsize_t start[3] = {hsize_t(first), 0, 0}, count[3] = {hsize_t(n), dims[1], dims[2]};
    h5::H5Id fspace = h5::check(H5Dget_space(masks.get()), "dataspace");
    h5::check(H5Sselect_hyperslab(fspace.get(), H5S_SELECT_SET, start, nullptr, count, nullptr), "select masks");
    h5::H5Id mspace = h5::check(H5Screate_simple(3, count, nullptr), "dataspace");
    if (n) h5::check(H5Dread(masks.get(), H5T_NATIVE_UINT8, mspace.get(), fspace.get(), H5P_DEFAULT, out.data()), "read masks");
    return out;
  } catch (const h5::H5Failure& e) {
    fail(path, e.what());
  }
}

std::vector<std::string> list_recordings(const std::string& dir) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) throw std::runtime_error(dir + ": not a directory");
  std::vector<std::string> out;
  for (const auto& e : fs::directory_iterator(dir, ec))
    if (e.is_regular_file() && e.path().filename().string().ends_with(kSuffix)) out.push_back(e.path().string());
  if (ec) throw std::runtime_error(dir + ": " + ec.message());
  if (out.empty()) throw std::runtime_error(dir + ": no recordings (*.yelan.h5; `yelan sim --grid ... --out-dir` writes them)");
  std::sort(out.begin(), out.end());
  return out;
}

void split_by_recording(const std::vector<std::string>& all, std::vector<std::string>& train,
                        std::vector<std::string>& val) {
  if (all.size() < 2)
    throw std::runtime_error("validation is split by recording: need two recordings or more (or give validation data)");
  train.clear(), val.clear();
  for (std::size_t i = 0; i < all.size(); ++i) (i % 10 == 9 ? val : train).push_back(all[i]);
  if (val.empty()) {
    val.push_back(train.back());
    train.pop_back();
  }
}

struct RecordingWindowStream::Open {
  h5::H5Id file, masks;  // opened once: the info and the masks come from it
  RecordingInfo info;
  std::unique_ptr<EventReader> reader;
  ToreVolume tore;
  std::vector<float> counts;
  std::vector<Event> buf;
  std::size_t first_mask = 0;  // the first mask time with warmup_s of events before it
  std::size_t index = 0;

  Open(const std::string& path, const WindowStreamOptions& o)
      : file(open_recording(path)), info(read_info(file.get(), path)), tore(info.camera.width, info.camera.height, o.tore) {
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
    out.resize(std::size_t(info.camera.width) * info.camera.height);
    const hsize_t start[3] = {hsize_t(m), 0, 0}, count[3] = {1, hsize_t(info.camera.height), hsize_t(info.camera.width)};
    h5::H5Id fspace = h5::check(H5Dget_space(masks.get()), "dataspace");
    h5::check(H5Sselect_hyperslab(fspace.get(), H5S_SELECT_SET, start, nullptr, count, nullptr), "select mask");
    h5::H5Id mspace = h5::check(H5Screate_simple(3, count, nullptr), "dataspace");
    h5::check(H5Dread(masks.get(), H5T_NATIVE_UINT8, mspace.get(), fspace.get(), H5P_DEFAULT, out.data()),
              info.path + ": read mask " + std::to_string(m));
  }

  // Joints linearly interpolated between the labels around t; a joint is valid when both are.
  void label_at(std::int64_t t, Joints13& j, std::array<std::uint8_t, kJointCount>& valid) const {
    const auto& lt = info.label_t;
    std::size_t b = std::size_t(std::upper_bound(lt.begin(), lt.end(), t) - lt.begin());
    std::size_t a = b == 0 ? 0 : b - 1;
    if (b >= lt.size()) b = lt.size() - 1;
    const double w = (b == a || lt[b] == lt[a]) ? 0.0 : double(t - lt[a]) / double(lt[b] - lt[a]);
    const double wa = 1 - std::clamp(w, 0.0, 1.0), wb = 1 - wa;
    for (int k = 0; k < kJointCount; ++k) {
      for (int d = 0; d < 3; ++d)
        j[k][d] = wa * info.joints[(a * kJointCount + k) * 3 + d] + wb * info.joints[(b * kJointCount + k) * 3 + d];
      valid[k] = info.valid[a * kJointCount + k] && info.valid[b * kJointCount + k];
    }
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
    r.feed(f.t_us);
    f.tore.resize(r.tore.volume_size());
    r.tore.readout(f.t_us, f.tore.data());
    r.read_mask(m, f.mask);
    if (!r.counts.empty()) {
      f.counts = r.counts;
      std::fill(r.counts.begin(), r.counts.end(), 0.f);
    } else {
      f.counts.clear();
    }
    r.label_at(f.t_us, f.joints_mm, f.valid);
  }
}

void RecordingWindowStream::next_from_cursor(SimWindow& out) {
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
  std::size_t first;
  bool fresh = true;
  if (slot >= S) {
    first = r.first_mask + j * slot + hash64(seed_, 0x5107 + b, visit * M + j) % (slot - S + 1);
    fresh = first < c.end;  // behind the reader: seek back
  } else {
    first = r.first_mask + hash64(seed_, 0x5107 + b, visit * M + j) % (frames - S + 1);
  }
  // Read on from the last window: the TORE then equals a fresh one started history_s before
  // (events older than TORE's tau read 0 either way), so a resumed run is bit-exact.
  if (!fresh && !r.counts.empty()) {
    r.feed(r.info.mask_t[first] - std::llround(1e6 / opt_.frame_hz));
    std::fill(r.counts.begin(), r.counts.end(), 0.f);
  }
  fill(r, first, fresh, out);
  c.end = first + S;
  ++k_;
}

void RecordingWindowStream::next(SimWindow& out) {
  const std::size_t S = std::size_t(opt_.window);
  if (opt_.shuffle && (opt_.cursors > 1 || opt_.windows_per_visit > 1)) return next_from_cursor(out);
  if (opt_.shuffle) {
    const std::size_t i = hash64(seed_, 0x5c3e, k_) % paths_.size();
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
