#include "engine/run/stream_eval.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>

#include "camera/sim/rng.h"

namespace yelan::run {

namespace {

struct Collect final : camera::sim::SimSink {
  std::vector<camera::Event>& out;
  explicit Collect(std::vector<camera::Event>& o) : out(o) {}
  void events(std::span<const camera::Event> ev) override { out.insert(out.end(), ev.begin(), ev.end()); }
};

double total(const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0); }

}  // namespace

std::vector<SimulatedScene> simulate_scenes(const std::vector<camera::sim::SimSpec>& scenes, std::uint64_t seed,
                                            double seconds, double warmup_s, std::ostream& progress) {
  std::vector<SimulatedScene> out;
  for (std::size_t i = 0; i < scenes.size(); ++i) {
    camera::sim::SimSpec s = scenes[i];
    s.seed = camera::sim::hash64(seed, 0x57e4, i) & 0xffffffffffffull;
    s.duration_s = warmup_s + seconds;
    SimulatedScene sc;
    sc.sim = std::make_unique<camera::sim::Simulator>(s);
    sc.warmup_s = warmup_s;
    Collect c(sc.events);
    sc.sim->run_until(s.duration_s, c);
    progress << "  simulated [" << (i + 1) << "/" << scenes.size() << "] " << s.name << ": " << sc.events.size() << " events\n";
    out.push_back(std::move(sc));
  }
  return out;
}

StreamEvalResult evaluate_stream(const std::string& weights, const std::vector<SimulatedScene>& scenes, const RunOptions& run) {
  namespace sim = camera::sim;
  using Clock = std::chrono::steady_clock;
  StreamEvalResult r;
  train::PoseMetrics paper, deployed;
  double tick_ms = 0, tore_ms = 0, s1_ms = 0, s2_ms = 0;
  RunStats crops;  // the crop tallies of every scene, for run::crop_share
  for (const SimulatedScene& sc : scenes) {
    const sim::Simulator& simulator = *sc.sim;
    const double end_s = simulator.duration_s();
    PosePipeline pipe(weights, simulator.camera().width, simulator.camera().height, run);
    std::vector<Pose> poses;
    const auto keep = [&](const Pose& p) { poses.push_back(p); };
    const auto t0 = Clock::now();
    pipe.push(sc.events, keep);
    pipe.finish(std::llround(end_s * 1e6), keep);
    r.wall_s += std::chrono::duration<double>(Clock::now() - t0).count();
    for (const Pose& p : poses) {
      const double t = double(p.t_us) * 1e-6;
      if (t < sc.warmup_s || t > end_s) continue;
      const sim::Label l = simulator.label_at(t);
      const bool dancer_seen = std::any_of(l.valid.begin(), l.valid.end(), [](auto v) { return bool(v); });
      if (!p.person) {
        r.person_missed += dancer_seen;
        continue;  // no joints: scored as a miss, not as NaN
      }
      r.person_found += dancer_seen;
      train::Pose13 truth, as_run, rescaled;
      std::array<std::uint8_t, train::kJoints> valid{};
      const double z_true = l.joints_mm[0].z();
      // The paper protocol: the prediction scaled to the true head depth (joints scale
      // linearly with the depth they were denormalised with).
      const double k = p.head_depth_mm > 0 && z_true > 1 ? z_true / p.head_depth_mm : 0;
      for (int j = 0; j < train::kJoints; ++j) {
        truth[j] = {l.joints_mm[j].x(), l.joints_mm[j].y(), l.joints_mm[j].z()};
        valid[j] = l.valid[j] && k > 0;
        for (int c = 0; c < 3; ++c) {
          as_run[j][c] = p.joints_mm[j][c];
          rescaled[j][c] = p.joints_mm[j][c] * k;
        }
      }
      paper.add(rescaled, truth, valid);
      deployed.add(as_run, truth, valid);
      ++r.poses_scored;
    }
    const RunStats& st = pipe.stats();
    r.ticks += st.ticks;
    r.mask_runs += st.mask_runs;
    r.stale += st.stale;
    crops.crop_area += st.crop_area;
    crops.crop_runs += st.crop_runs;
    tick_ms += total(st.times.tick_ms);
    tore_ms += total(st.times.tore_ms);
    s1_ms += total(st.times.stage1_ms);
    s2_ms += total(st.times.stage2_ms);
  }
  r.paper = paper.scores();
  r.deployed = deployed.scores();
  const double timed = double(std::max<std::uint64_t>(1, r.ticks - r.stale));  // stale ticks run no stage
  r.mask_run_fraction = double(r.mask_runs) / timed;
  r.ms_per_tick = tick_ms / timed;
  r.tore_ms = tore_ms / timed;
  r.stage1_ms = s1_ms / timed;
  r.stage2_ms = s2_ms / timed;
  r.crop_share = crop_share(crops);
  return r;
}

}  // namespace yelan::run
