#include "benchmarks/sim/bench_sim.h"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <sstream>

#include "camera/io/event_reader.h"
#include "camera/sim/presets.h"
#include "benchmarks/bench_util.h"
#include "engine/cli/args.h"
#include "engine/threads.h"

namespace yelan::bench {
namespace {

namespace sim = camera::sim;

struct CountSink final : sim::SimSink {
  std::uint64_t count = 0;
  void events(std::span<const camera::Event> ev) override { count += ev.size(); }
};

struct Row {
  std::string preset;
  int threads;
  double sim_s, wall_s, render_s, pixel_s, ev_per_s, mean_step_ms;
  std::uint64_t samples;
};

// Events per second of the real DAVIS346 recording (a person moving; SPEC's yardstick).
double real_event_rate(std::string& what) {
  const std::filesystem::path p = std::filesystem::path(YELAN_SOURCE_DIR) / ".." / "shared" / "data" / "events" /
                                  "aestream_davis.aedat4";
  if (!std::filesystem::exists(p)) return 0;
  auto r = camera::open_event_file(p.string());
  std::vector<camera::Event> ev;
  std::uint64_t n = 0;
  std::int64_t first = 0, last = 0;
  while (r->read(ev, 1 << 16) > 0) {
    if (n == 0) first = ev.front().t;
    last = ev.back().t;
    n += ev.size();
    ev.clear();
  }
  what = p.lexically_normal().filename().string();
  return last > first ? double(n) / (double(last - first) * 1e-6) : 0;
}

}  // namespace

int run_sim_bench(const std::vector<std::string>& argv, std::ostream& out, std::ostream& err) {
  cli::Args args("bench sim", argv, {"--duration", "--threads-list", "--character", "--motion", "--view", "--presets"}, {"--json"});
  args.expect_positionals(0, 0);
  const double duration = args.number_or("--duration", 2, 0, 3600, true);
  if (!(duration > 0 && duration < 3600)) throw cli::UsageError("--duration: seconds in (0, 3600)");
  const std::vector<int> threads = threads_list(args);
  const std::string character = args.value_or("--character", "ben"), view = args.value_or("--view", "front");
  std::string motion = args.value_or("--motion", "05_04");
  if (motion != "dance" && !std::filesystem::exists(std::filesystem::path(sim::default_mocap_dir()) / (motion + ".bvh"))) {
    err << "no " << motion << ".bvh in " << sim::default_mocap_dir() << ": benchmarking a procedural dance instead\n";
    motion = "dance";
  }
  // The lighting x background grid of one dancer, or the scenes named by --presets (the
  // costly kinds: flicker, a moving camera, a furnished room).
  std::vector<std::string> presets;
  if (const auto named = args.value("--presets")) {
    std::stringstream list(*named);
    for (std::string p; std::getline(list, p, ',');)
      if (!p.empty()) presets.push_back(p);
    if (presets.empty()) throw cli::UsageError("--presets: a comma-separated list of presets");
    for (const auto& p : presets) sim::preset_spec(p);  // an unknown name fails before any run
  } else {
    for (const char* light : {"high", "medium", "low"})
      for (const char* bg : {"static", "dynamic"}) presets.push_back(character + "-" + motion + "-" + view + "-" + light + "-" + bg);
  }
  std::vector<Row> rows;
  const int saved = yelan::threads();
  for (const std::string& preset : presets)
      for (int t : threads) {
        set_threads(t);
        sim::SimSpec spec = sim::preset_spec(preset);
        spec.duration_s = duration;
        spec.seed = 1;
        sim::Simulator s(spec);
        CountSink sink;
        const auto t0 = std::chrono::steady_clock::now();
        s.run_until(duration, sink);
        const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        const auto& st = s.stats();
        rows.push_back({spec.name, t, duration, wall, st.render_wall_s, st.pixel_wall_s, double(sink.count) / duration,
                        st.mean_step_s * 1e3, st.samples});
        err << "  " << spec.name << " x" << t << ": " << duration / wall << "x real time\n";
      }
  set_threads(saved);
  std::string real_name;
  const double real_rate = real_event_rate(real_name);
  if (args.flag("--json")) {
    out << "{\"real_recording\": \"" << real_name << "\", \"real_events_per_s\": " << real_rate << ", \"rows\": [\n";
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const Row& r = rows[i];
      out << "  {\"preset\": \"" << r.preset << "\", \"threads\": " << r.threads << ", \"simulated_s\": " << r.sim_s
          << ", \"wall_s\": " << r.wall_s << ", \"realtime_factor\": " << r.sim_s / r.wall_s
          << ", \"render_share\": " << r.render_s / r.wall_s << ", \"pixel_share\": " << r.pixel_s / r.wall_s
          << ", \"samples\": " << r.samples << ", \"mean_step_ms\": " << r.mean_step_ms
          << ", \"events_per_s\": " << r.ev_per_s;
      if (real_rate > 0) out << ", \"events_vs_real\": " << r.ev_per_s / real_rate;
      out << "}" << (i + 1 < rows.size() ? "," : "") << "\n";
    }
    out << "]}\n";
    return 0;
  }
  out << "preset                                       threads  x real time  render  pixel  step ms  Mev/s";
  out << (real_rate > 0 ? "  vs real\n" : "\n");
  for (const Row& r : rows) {
    char line[256];
    std::snprintf(line, sizeof line, "%-44s %7d %12.2f %6.0f%% %5.0f%% %8.3f %6.3f", r.preset.c_str(), r.threads,
                  r.sim_s / r.wall_s, 100 * r.render_s / r.wall_s, 100 * r.pixel_s / r.wall_s, r.mean_step_ms,
                  r.ev_per_s / 1e6);
    out << line;
    if (real_rate > 0) {
      std::snprintf(line, sizeof line, " %7.2fx", r.ev_per_s / real_rate);
      out << line;
    }
    out << "\n";
  }
  if (real_rate > 0) out << "real DAVIS346 recording " << real_name << ": " << real_rate / 1e6 << " Mev/s\n";
  return 0;
}

}  // namespace yelan::bench
