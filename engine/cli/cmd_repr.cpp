// `yelan repr`: representation volumes (TORE, count frames, voxel grids, time surfaces)
// read out of an event file at chosen times, into HDF5 (camera/repr/volume_file.h) and
// optionally PNG pictures. Streams the file in batches: memory is the representation's
// state plus, for windowed types, the events of one window.
#include <charconv>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <memory>
#include <sstream>

#include "camera/io/event_reader.h"
#include "camera/repr/filters.h"
#include "camera/repr/frames.h"
#include "camera/repr/preview_png.h"
#include "camera/repr/time_surface.h"
#include "camera/repr/tore.h"
#include "camera/repr/volume_file.h"
#include "engine/cli/args.h"
#include "engine/cli/cli.h"
#include "engine/cli/handlers.h"
#include "engine/cli/output_path.h"
#include "engine/threads.h"

namespace yelan::cli {
namespace {

using camera::Event;
constexpr std::size_t kBatch = 1 << 16;

std::int64_t parse_i64(const std::string& option, const std::string& text, std::int64_t min, std::int64_t max) {
  std::int64_t v = 0;
  auto [p, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (text.empty() || ec != std::errc() || p != text.data() + text.size() || v < min || v > max)
    throw UsageError("option " + option + " expects an integer in [" + std::to_string(min) + ", " +
                     std::to_string(max) + "], got '" + text + "'");
  return v;
}

std::vector<std::int64_t> parse_times(const std::string& list) {
  std::vector<std::int64_t> out;
  std::size_t start = 0;
  while (start <= list.size()) {
    const std::size_t comma = std::min(list.find(',', start), list.size());
    out.push_back(parse_i64("--at", list.substr(start, comma - start), -(std::int64_t{1} << 62),
                            std::int64_t{1} << 62));
    if (out.size() > 1 && out.back() < out[out.size() - 2])
      throw UsageError("--at times must be in increasing order (" + std::to_string(out[out.size() - 2]) +
                       " then " + std::to_string(out.back()) + ")");
    start = comma + 1;
  }
  return out;
}

// One representation behind a common face: fed events in time order, read out at T.
class Representation {
 public:
  virtual ~Representation() = default;
  virtual int channels() const = 0;
  virtual void push(std::span<const Event> events) = 0;
  virtual void readout(std::int64_t t, float* out) = 0;
  virtual std::vector<std::uint8_t> preview(const float* volume, int width, int height) const = 0;
  virtual std::uint64_t out_of_range() const = 0;
};

class ToreRepr : public Representation {
 public:
  ToreRepr(int w, int h, int k, std::int64_t tau, bool baldwin) : tore_(w, h, {k, tau}), baldwin_(baldwin) {}
  int channels() const override { return tore_.channels(); }
  void push(std::span<const Event> ev) override { tore_.update(ev); }
  void readout(std::int64_t t, float* out) override {
    baldwin_ ? tore_.readout_baldwin(t, out, {}, threads()) : tore_.readout(t, out, threads());
  }
  std::vector<std::uint8_t> preview(const float* v, int w, int h) const override {
    // Baldwin's values run from 0 (new) to ~10.4 (old or missing): show the newest as bright.
    if (baldwin_) {
      std::vector<float> flipped(2 * std::size_t(w) * h);
      const std::size_t plane = std::size_t(w) * h;
      const float top = std::log(5e6f + 1) - std::log(151.f);
      for (std::size_t i = 0; i < plane; ++i) {
        flipped[i] = 1.f - v[i] / top;
        flipped[plane + i] = 1.f - v[std::size_t(tore_.k()) * plane + i] / top;
      }
      return camera::preview_rgb(flipped.data(), w, h, camera::PreviewStyle::polarity_pair, 0, 1);
    }
    return camera::preview_rgb(v, w, h, camera::PreviewStyle::polarity_pair, 0, tore_.k());
  }
  std::uint64_t out_of_range() const override { return tore_.out_of_range(); }

 private:
  camera::ToreVolume tore_;
  bool baldwin_;
};

class SurfaceRepr : public Representation {
 public:
  SurfaceRepr(int w, int h, std::int64_t tau) : ts_(w, h, tau) {}
  int channels() const override { return 2; }
  void push(std::span<const Event> ev) override { ts_.update(ev); }
  void readout(std::int64_t t, float* out) override { ts_.readout(t, out); }
  std::vector<std::uint8_t> preview(const float* v, int w, int h) const override {
    return camera::preview_rgb(v, w, h, camera::PreviewStyle::polarity_pair, 0, 1);
  }
  std::uint64_t out_of_range() const override { return ts_.out_of_range(); }

 private:
  camera::TimeSurface ts_;
};

// Count frames (a time window or the last N events) and voxel grids (a time window).
class WindowRepr : public Representation {
 public:
  WindowRepr(int w, int h, camera::EventWindow window, int bins, std::int64_t span)
      : w_(w), h_(h), window_(std::move(window)), bins_(bins), span_(span) {}
  int channels() const override { return bins_ ? bins_ : 1; }
  void push(std::span<const Event> ev) override {
    for (const Event& e : ev) window_.push(e);
  }
  void readout(std::int64_t t, float* out) override {
    window_.drop_before(t);
    auto ev = window_.events();
    dropped_ += bins_ ? camera::voxel_grid(ev, w_, h_, bins_, t - span_, t, out)
                      : camera::count_frame(ev, w_, h_, out);
  }
  std::vector<std::uint8_t> preview(const float* v, int w, int h) const override {
    if (!bins_) return camera::preview_rgb(v, w, h, camera::PreviewStyle::grey, 0);
    return camera::preview_rgb(v, w, h, camera::PreviewStyle::signed_value, bins_ - 1);  // newest bin
  }
  // Events outside the sensor are skipped at each read-out that sees them.
  std::uint64_t out_of_range() const override { return dropped_; }

 private:
  int w_, h_;
  camera::EventWindow window_;
  int bins_;
  std::int64_t span_;
  std::uint64_t dropped_ = 0;
};

// Optional noise filters in front of the representation.
struct FilterChain {
  std::unique_ptr<camera::BackgroundActivityFilter> baf;
  std::unique_ptr<camera::RefractoryFilter> refractory;
  std::uint64_t removed = 0;
  void apply(std::vector<Event>& batch) {
    const std::size_t before = batch.size();
    if (refractory) refractory->apply(batch);
    if (baf) baf->apply(batch);
    removed += before - batch.size();
  }
};

// When the next volume is due: a fixed list, or every 1/F s from the first event.
class Schedule {
 public:
  explicit Schedule(std::vector<std::int64_t> at) : at_(std::move(at)) {}
  explicit Schedule(double fps) : period_(1e6 / fps) {}
  void start(std::int64_t t_first) {
    if (period_ > 0 && !started_) t0_ = t_first, started_ = true;
  }
  // nullopt when there is nothing more to read out (fps: not before the first event).
  std::optional<std::int64_t> next() const {
    if (period_ > 0)
      return started_ ? std::optional(t0_ + std::llround(double(i_ + 1) * period_)) : std::nullopt;
    return i_ < at_.size() ? std::optional(at_[i_]) : std::nullopt;
  }
  void advance() { ++i_; }
  bool by_rate() const { return period_ > 0; }

 private:
  std::vector<std::int64_t> at_;
  double period_ = 0;
  std::int64_t t0_ = 0;
  bool started_ = false;
  std::size_t i_ = 0;
};

int run_repr(const std::vector<std::string>& argv, std::ostream& out) {
  Args args("repr", argv,
            {"--type", "--k", "--bins", "--tau-us", "--window-us", "--events", "--width", "--height",
             "--at", "--fps", "--png", "--baf-us", "--refractory-us", "--max-volumes"},
            {"--quiet"});
  args.expect_positionals(2, 2);
  const std::string in = args.positionals()[0], out_path = args.positionals()[1];
  const std::string type = args.value_or("--type", "");
  if (type != "tore" && type != "tore-baldwin" && type != "count" && type != "voxel" && type != "surface")
    throw UsageError("--type expects tore, tore-baldwin, count, voxel or surface" +
                     (type.empty() ? std::string() : ", got '" + type + "'") + " (see 'yelan repr --help')");
  if (args.value("--at").has_value() == args.value("--fps").has_value())
    throw UsageError("give exactly one of --at T1,T2,... and --fps F (see 'yelan repr --help')");
  std::optional<Schedule> schedule;
  if (auto at = args.value("--at")) {
    schedule.emplace(parse_times(*at));
  } else {
    const std::string f = *args.value("--fps");
    char* end = nullptr;
    const double fps = std::strtod(f.c_str(), &end);
    if (f.empty() || *end || !(fps > 0) || fps > 1e6)
      throw UsageError("--fps expects a rate in (0, 1e6] per second, got '" + f + "'");
    schedule.emplace(fps);
  }
  if (type != "count" && args.value("--events")) throw UsageError("--events applies to --type count only");
  if (type != "voxel" && args.value("--bins")) throw UsageError("--bins applies to --type voxel only");
  if (type.rfind("tore", 0) != 0 && args.value("--k")) throw UsageError("--k applies to --type tore only");
  check_output("OUT", out_path, {in});

  auto reader = camera::open_event_file(in);
  int width = reader->info().width, height = reader->info().height;
  width = args.int_value_or("--width", width, 1, 65536);
  height = args.int_value_or("--height", height, 1, 65536);
  if (width <= 0 || height <= 0)
    throw UsageError(in + " does not state its sensor size: give --width and --height");

  std::unique_ptr<Representation> repr;
  std::vector<std::pair<std::string, std::int64_t>> attrs = {{"width", width}, {"height", height}};
  if (type == "tore" || type == "tore-baldwin") {
    const int k = args.int_value_or("--k", 3, 1, 64);
    const std::int64_t tau = parse_i64("--tau-us", args.value_or("--tau-us", "5000000"), 2, 2147483647);
    repr = std::make_unique<ToreRepr>(width, height, k, tau, type == "tore-baldwin");
    attrs.insert(attrs.end(), {{"k", k}, {"tau_us", tau}});
  } else if (type == "surface") {
    const std::int64_t tau = parse_i64("--tau-us", args.value_or("--tau-us", "50000"), 1, std::int64_t{1} << 40);
    repr = std::make_unique<SurfaceRepr>(width, height, tau);
    attrs.push_back({"tau_us", tau});
  } else {
    if (args.value("--tau-us")) throw UsageError("--tau-us applies to --type tore and surface only");
    const std::int64_t span = parse_i64("--window-us", args.value_or("--window-us", "20000"), 1, std::int64_t{1} << 40);
    if (type == "count" && args.value("--events")) {
      if (args.value("--window-us")) throw UsageError("give --window-us or --events, not both");
      const int n = args.int_value_or("--events", 7500, 1, 100'000'000);
      repr = std::make_unique<WindowRepr>(width, height, camera::EventWindow::by_count(n), 0, 0);
      attrs.push_back({"window_events", n});
    } else {
      const int bins = type == "voxel" ? args.int_value_or("--bins", 5, 1, 1024) : 0;
      repr = std::make_unique<WindowRepr>(width, height, camera::EventWindow::by_time(span), bins, span);
      attrs.push_back({"window_us", span});
      if (bins) attrs.push_back({"bins", bins});
    }
  }
  FilterChain filters;
  constexpr std::int64_t kMaxSpan = std::int64_t{1} << 40;
  if (auto v = args.value("--baf-us")) {
    const std::int64_t window = parse_i64("--baf-us", *v, 0, kMaxSpan);
    filters.baf = std::make_unique<camera::BackgroundActivityFilter>(width, height, window);
    attrs.push_back({"baf_us", window});
  }
  if (auto v = args.value("--refractory-us")) {
    const std::int64_t period = parse_i64("--refractory-us", *v, 0, kMaxSpan);
    filters.refractory = std::make_unique<camera::RefractoryFilter>(width, height, period);
    attrs.push_back({"refractory_us", period});
  }
  // A corrupt timestamp far in the future must not turn --fps into a disk-filling loop.
  const std::int64_t max_volumes = parse_i64("--max-volumes", args.value_or("--max-volumes", "100000"), 1,
                                             std::int64_t{1} << 40);
  std::optional<std::filesystem::path> png_dir;
  if (auto d = args.value("--png")) {
    png_dir = *d;
    std::error_code ec;
    std::filesystem::create_directories(*png_dir, ec);
    if (ec) throw std::runtime_error("--png: cannot create directory " + *d + ": " + ec.message());
  }

  {
    camera::VolumeFileWriter writer(out_path, type, repr->channels(), height, width, attrs);
    std::vector<float> volume(std::size_t(repr->channels()) * width * height);
    auto emit = [&](std::int64_t t) {
      if (writer.count() >= max_volumes)
        throw std::runtime_error("more than " + std::to_string(max_volumes) + " volumes to write (the " +
                                 std::to_string(max_volumes + 1) + "th at t = " + std::to_string(t) +
                                 " us); raise --max-volumes if that is intended");
      repr->readout(t, volume.data());
      writer.append(t, volume.data());
      if (png_dir) {
        char name[32];
        std::snprintf(name, sizeof name, "%06lld.png", static_cast<long long>(writer.count() - 1));
        camera::write_png_rgb((*png_dir / name).string(), width, height, repr->preview(volume.data(), width, height));
      }
      schedule->advance();
    };

    std::vector<Event> batch;
    std::uint64_t events = 0;
    std::int64_t t_last = std::numeric_limits<std::int64_t>::min();
    while (true) {
      batch.clear();
      if (reader->read(batch, kBatch) == 0) break;
      if (events == 0) schedule->start(batch.front().t);
      if (!schedule->next()) break;  // every --at time is written: the rest cannot matter
      events += batch.size();
      for (const Event& e : batch) t_last = std::max(t_last, e.t);
      filters.apply(batch);
      // Feed events up to each due time, read out, go on: a volume at T holds every event
      // with t <= T (the stream is in time order; the reader counts any disorder).
      std::span<const Event> rest(batch);
      while (!rest.empty()) {
        auto due = schedule->next();
        std::size_t n = rest.size();
        if (due) {
          n = 0;
          while (n < rest.size() && rest[n].t <= *due) ++n;
        }
        repr->push(rest.first(n));
        rest = rest.subspan(n);
        if (!rest.empty()) emit(*due);
      }
    }
    // After the last event: --fps stops at the last event's time, --at reads out every
    // time asked for (later ones see the final state).
    while (auto due = schedule->next()) {
      if (schedule->by_rate() && *due > t_last) break;
      emit(*due);
    }
    writer.finish();

    if (!args.flag("--quiet")) {
      const auto& w = reader->warnings();
      out << "yelan repr: " << writer.count() << " volume(s) of " << repr->channels() << "x" << height << "x"
          << width << " (" << type << ") from " << events << " events of " << in << " -> " << out_path << "\n";
      if (writer.count() == 0)
        out << "  no read-out time fell within the events (" << (schedule->by_rate() ? "--fps" : "--at") << ")\n";
      if (filters.removed) out << "  filters removed " << filters.removed << " events\n";
      if (w.total()) out << "  reader warnings: " << w.backwards << " backwards, " << w.out_of_range
                         << " out of range, " << w.skipped << " skipped (first: " << w.first << ")\n";
      if (repr->out_of_range()) out << "  " << repr->out_of_range() << " events outside " << width << "x"
                                    << height << " were skipped\n";
      if (png_dir) out << "  pictures in " << png_dir->string() << "\n";
    }
  }
  return 0;
}

}  // namespace

// Bad input files exit 2, like bad usage (SPEC: exit codes).
int cmd_repr(const std::vector<std::string>& argv, std::ostream& out, std::ostream& err) {
  try {
    return run_repr(argv, out);
  } catch (const camera::FormatError& e) {
    err << "yelan: error: " << printable(e.what()) << "\n";
    return 2;
  }
}

}  // namespace yelan::cli
