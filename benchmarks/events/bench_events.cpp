#include "benchmarks/events/bench_events.h"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <unistd.h>
#include <chrono>
#include <cstring>
#include <iomanip>
#include <random>
#include <sstream>

#include "camera/event.h"
#include "camera/io/event_reader.h"
#include "camera/io/event_writer.h"
#include "camera/repr/filters.h"
#include "camera/repr/tore.h"
#include "engine/cli/args.h"
#include "kernels/cpu.h"

namespace yelan::bench {
namespace {

using Clock = std::chrono::steady_clock;
using camera::Event;

struct Record {
  std::string name, unit;
  double value;          // in `unit`
  double seconds;        // median time of one repetition of the measured work
  double baseline_s;     // median time of the memcpy/memset of the same bytes
  std::string baseline;  // what the baseline was
  std::size_t bytes;     // bytes the baseline moved
};

template <class F>
double median_seconds(int reps, F&& work) {
  std::vector<double> t;
  for (int r = 0; r < reps; ++r) {
    auto t0 = Clock::now();
    work();
    t.push_back(std::chrono::duration<double>(Clock::now() - t0).count());
  }
  std::sort(t.begin(), t.end());
  return t[t.size() / 2];
}

// Uniformly random pixels and polarities, 1 us apart: the worst case for the FIFO's
// locality (a real scene hits neighbouring pixels and is faster).
std::vector<Event> random_stream(std::size_t n, int width, int height, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::vector<Event> ev(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint64_t r = rng();
    ev[i] = Event{std::int64_t(i), std::uint16_t((r & 0xffffffff) % width),
                  std::uint16_t(((r >> 32) & 0x7fffffff) % height), std::uint8_t(r >> 63)};
  }
  return ev;
}

// A sweeping vertical bar about 8 px wide: events cluster like a moving edge.
std::vector<Event> edge_stream(std::size_t n, int width, int height, unsigned seed) {
  std::mt19937 rng(seed);
  std::vector<Event> ev(n);
  for (std::size_t i = 0; i < n; ++i) {
    const int centre = int((i / 2000) % std::size_t(width));
    const int x = std::clamp(centre + int(rng() % 8) - 4, 0, width - 1);
    ev[i] = Event{std::int64_t(i), std::uint16_t(x), std::uint16_t(rng() % height), std::uint8_t(rng() & 1)};
  }
  return ev;
}

void print_text(const std::vector<Record>& recs, std::ostream& out) {
  for (const Record& r : recs) {
    out << std::left << std::setw(34) << r.name << std::right << std::fixed << std::setprecision(3)
        << std::setw(12) << r.value << " " << std::setw(10) << std::left << r.unit << std::right
        << "  time " << std::setprecision(4) << r.seconds * 1e3 << " ms, " << r.baseline << " of "
        << r.bytes << " B " << r.baseline_s * 1e3 << " ms, ratio " << std::setprecision(2)
        << r.seconds / r.baseline_s;
    if (r.baseline == "cat")
      out << " (" << std::setprecision(1) << r.bytes / r.seconds / 1e6 << " MB/s vs cat " << r.bytes / r.baseline_s / 1e6
          << " MB/s)";
    out << "\n";
  }
}

void print_json(const std::vector<Record>& recs, std::ostream& out) {
  out << "[\n";
  for (std::size_t i = 0; i < recs.size(); ++i) {
    const Record& r = recs[i];
    out << std::setprecision(9) << "  {\"name\": \"" << r.name << "\", \"unit\": \"" << r.unit
        << "\", \"value\": " << r.value << ", \"seconds\": " << r.seconds
        << ", \"baseline\": \"" << r.baseline << "\", \"baseline_bytes\": " << r.bytes
        << ", \"baseline_seconds\": " << r.baseline_s
        << ", \"ratio_to_baseline\": " << r.seconds / r.baseline_s;
    if (r.baseline == "cat") out << ", \"mb_per_s\": " << r.bytes / r.seconds / 1e6 << ", \"cat_mb_per_s\": " << r.bytes / r.baseline_s / 1e6;
    out << "}"
        << (i + 1 < recs.size() ? "," : "") << "\n";
  }
  out << "]\n";
}

// Reading whole files through open_event_file, against a plain read of the same bytes
// ("cat": fread into a 1 MiB buffer) measured right before it: the formats' decoding cost.
void bench_reading(int reps, std::size_t n, std::vector<Record>& recs) {
  namespace fs = std::filesystem;
  std::vector<std::pair<std::string, std::string>> files;  // name, path
  const char* env = std::getenv("YELAN_SHARED_DATA");
  const fs::path shared = fs::path(env ? env : YELAN_SOURCE_DIR "/../shared/data") / "events";
  for (const char* f : {"aestream_davis.aedat4", "evt2_sample.raw", "evt3_sample.raw"})
    if (fs::exists(shared / f)) files.emplace_back(std::string("real:") + f, (shared / f).string());
  // Our writable formats, from one synthetic moving-edge stream.
  const fs::path dir = fs::temp_directory_path() / ("yelan-bench-read-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const auto stream = edge_stream(n, 346, 260, 3);
  camera::StreamInfo info;
  info.width = 346;
  info.height = 260;
  for (const char* ext : {"yelan.h5", "aedat4", "txt"}) {
    const std::string path = (dir / (std::string("edge.") + ext)).string();
    auto w = camera::open_event_writer(path, info);
    w->write(stream);
    w->close();
    files.emplace_back(std::string("synthetic:edge.") + ext, path);
  }
  std::vector<char> buf(1 << 20);
  for (const auto& [name, path] : files) {
    const std::size_t bytes = fs::file_size(path);
    const double cat = median_seconds(reps, [&] {
      FILE* f = std::fopen(path.c_str(), "rb");
      if (!f) return;
      while (std::fread(buf.data(), 1, buf.size(), f) == buf.size()) {}
      std::fclose(f);
    });
    std::size_t events = 0;
    const double s = median_seconds(reps, [&] {
      auto reader = camera::open_event_file(path);
      std::vector<Event> ev;
      events = 0;
      while (reader->read(ev, 1 << 16) > 0) {
        events += ev.size();
        ev.clear();
      }
    });
    recs.push_back({"read " + name, "Mev/s", events / s / 1e6, s, cat, "cat", bytes});
  }
  fs::remove_all(dir);
}

}  // namespace

// Usage errors are thrown (cli::UsageError), so nothing is written to the error stream.
int run_events_bench(const std::vector<std::string>& argv, std::ostream& out, std::ostream& /*err*/) {
  cli::Args args("bench events", argv, {"--events", "--reps", "--k", "--width", "--height", "--file", "--threads"},
                 {"--quick", "--json", "--no-read"});
  args.expect_positionals(0, 0);
  const bool quick = args.flag("--quick");
  const int n = args.int_value_or("--events", quick ? 1'000'000 : 8'000'000, 1000, 200'000'000);
  const int reps = args.int_value_or("--reps", quick ? 5 : 11, 1, 1000);
  const int k = args.int_value_or("--k", 3, 1, 64);
  const int width = args.int_value_or("--width", 346, 1, 8192);
  const int height = args.int_value_or("--height", 260, 1, 8192);
  const int threads = args.int_value_or("--threads", 1, 1, 1024);  // extra read-out records

  std::vector<std::pair<std::string, std::vector<Event>>> streams = {
      {"tore_update_random", random_stream(n, width, height, 1)},
      {"tore_update_edge", edge_stream(n, width, height, 2)}};
  if (auto file = args.value("--file")) {
    // A real recording, replayed from memory (its first --events events).
    auto reader = camera::open_event_file(*file);
    if (reader->info().width != width || reader->info().height != height)
      throw cli::UsageError("--file " + *file + " is " + std::to_string(reader->info().width) + "x" +
                            std::to_string(reader->info().height) + "; give the same --width/--height");
    std::vector<Event> ev;
    while (ev.size() < std::size_t(n) && reader->read(ev, std::size_t(n) - ev.size()) > 0) {}
    streams.emplace_back("tore_update_file", std::move(ev));
  }

  std::vector<Record> recs;
  camera::ToreVolume tore(width, height, {k});

  // Baseline for updates: copying the event bytes once (the least any update must read).
  for (auto& [name, stream] : streams) {
    std::vector<Event> copy(stream.size());
    const std::size_t bytes = stream.size() * sizeof(Event);
    const double base = median_seconds(reps, [&] { std::memcpy(copy.data(), stream.data(), bytes); });
    tore.reset();
    tore.update(stream);  // warm the FIFO pages
    const double s = median_seconds(reps, [&] { tore.update(stream); });
    recs.push_back({name, "Mev/s", stream.size() / s / 1e6, s, base, "memcpy", bytes});
  }
  // The filters on the edge stream, for scale (their own state: one int64 per pixel).
  {
    const auto& stream = streams[1].second;
    std::vector<Event> copy(stream.size());
    const std::size_t bytes = stream.size() * sizeof(Event);
    const double base = median_seconds(reps, [&] { std::memcpy(copy.data(), stream.data(), bytes); });
    camera::BackgroundActivityFilter baf(width, height);
    std::size_t kept = 0;
    const double s_baf = median_seconds(reps, [&] {
      baf.reset();
      kept = 0;
      for (const Event& e : stream) kept += baf.accept(e);
    });
    recs.push_back({"baf_filter_edge", "Mev/s", stream.size() / s_baf / 1e6, s_baf, base, "memcpy", bytes});
    camera::RefractoryFilter refractory(width, height, 1000);
    const double s_ref = median_seconds(reps, [&] {
      refractory.reset();
      kept = 0;
      for (const Event& e : stream) kept += refractory.accept(e);
    });
    recs.push_back({"refractory_filter_edge", "Mev/s", stream.size() / s_ref / 1e6, s_ref, base, "memcpy", bytes});
  }

  // Read-out of a volume after a full stream, against memset of the volume's bytes.
  std::vector<float> volume(tore.volume_size());
  const std::size_t bytes = volume.size() * sizeof(float);
  const int per_rep = quick ? 20 : 50;
  const std::int64_t t_read = n;  // just after the stream's last event
  const double base =
      median_seconds(reps, [&] {
        for (int i = 0; i < per_rep; ++i) std::memset(volume.data(), i, bytes);
      }) / per_rep;
  for (bool baldwin : {false, true}) {
    const double s = median_seconds(reps, [&] {
                       for (int i = 0; i < per_rep; ++i)
                         baldwin ? tore.readout_baldwin(t_read + i, volume.data())
                                 : tore.readout(t_read + i, volume.data());
                     }) / per_rep;
    recs.push_back({baldwin ? "tore_readout_baldwin" : "tore_readout", "ms/volume", s * 1e3, s,
                    base, "memset", bytes});
  }
  if (threads > 1) {
    const double s = median_seconds(reps, [&] {
                       for (int i = 0; i < per_rep; ++i) tore.readout(t_read + i, volume.data(), threads);
                     }) / per_rep;
    recs.push_back({"tore_readout_" + std::to_string(threads) + "threads", "ms/volume", s * 1e3, s, base,
                    "memset", bytes});
  }

  if (!args.flag("--no-read")) bench_reading(quick ? 3 : 5, quick ? 500'000 : 2'000'000, recs);

  if (args.flag("--json")) {
    print_json(recs, out);
  } else {
    out << "events bench: " << width << "x" << height << ", K=" << k << ", " << n
        << " events per stream, median of " << reps << ", 1 thread unless named, isa "
        << kernels::isa_name(kernels::active_isa()) << "\n";
    print_text(recs, out);
  }
  return 0;
}

}  // namespace yelan::bench
