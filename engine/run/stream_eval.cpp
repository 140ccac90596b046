#include "engine/run/stream_eval.h"

#include <algorithm>
#include <chrono>
#include <iomanip>
#include <sstream>
#include <cmath>
#include <numeric>
#include <optional>

#include "camera/sim/recording_reader.h"
#include "camera/sim/rng.h"
#include "engine/run/presence.h"
#include "engine/run/true_masks.h"
#include "engine/train/mask_overlap.h"

namespace yelan::run {

namespace {

struct Collect final : camera::sim::SimSink {
  SimulatedScene& out;
  explicit Collect(SimulatedScene& o) : out(o) {}
  void events(std::span<const camera::Event> ev) override { out.events.insert(out.events.end(), ev.begin(), ev.end()); }
  void mask(std::int64_t t_us, const camera::sim::RenderedFrame& frame) override {
    out.mask_t.push_back(t_us);
    out.dancer_shows.push_back(std::any_of(frame.mask.begin(), frame.mask.end(), [](std::uint8_t v) { return v != 0; }));
    if (!out.sim->spec().dancer || t_us < std::llround(out.warmup_s * 1e6) - 1000) return;
    if (out.mask_bits.empty()) out.first_bits_tick = out.mask_t.size() - 1;
    const std::size_t n = frame.mask.size(), base = out.mask_bits.size();
    out.mask_bits.resize(base + (n + 63) / 64, 0);
    for (std::size_t i = 0; i < n; ++i)
      if (frame.mask[i]) out.mask_bits[base + i / 64] |= std::uint64_t(1) << (i % 64);
  }
};

// Whether the dancer shows at t_us: the latest mask tick at or before it (the first one
// before any); true without masks.
bool shows_at(const std::vector<std::int64_t>& mask_t, const std::vector<std::uint8_t>& shows, std::int64_t t_us) {
  if (mask_t.empty()) return true;
  const auto it = std::upper_bound(mask_t.begin(), mask_t.end(), t_us);
  return shows[it == mask_t.begin() ? 0 : std::size_t(it - mask_t.begin()) - 1] != 0;
}

double total(const std::vector<double>& v) { return std::accumulate(v.begin(), v.end(), 0.0); }

}  // namespace

bool SimulatedScene::true_mask(std::size_t k, std::vector<std::uint8_t>& out) const {
  const std::size_t n = std::size_t(sim->camera().width) * std::size_t(sim->camera().height), words = (n + 63) / 64;
  if (k < first_bits_tick || (k - first_bits_tick + 1) * words > mask_bits.size()) return false;
  const std::uint64_t* w = &mask_bits[(k - first_bits_tick) * words];
  out.resize(n);
  for (std::size_t i = 0; i < n; ++i) out[i] = std::uint8_t((w[i / 64] >> (i % 64)) & 1);
  return true;
}

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
    Collect c(sc);
    sc.sim->run_until(s.duration_s, c);
    progress << "  simulated [" << (i + 1) << "/" << scenes.size() << "] " << s.name << ": " << sc.events.size() << " events\n";
    out.push_back(std::move(sc));
  }
  return out;
}

namespace {

// Scores poses against labels and sums what the runs cost; shared by simulated scenes and
// recordings on disk.
struct StreamScorer {
  StreamEvalResult r;
  train::PoseMetrics paper, deployed;
  std::vector<double> depth_ratio;  // estimated / true head depth, per scored pose
  double depth_abs = 0;
  double tick_ms = 0, tore_ms = 0, s1_ms = 0, s2_ms = 0;
  RunStats crops;  // the crop tallies of every run, for run::crop_share
  train::MaskOverlap overlap;  // the masks in use against the true ones
  std::map<std::string, train::MaskOverlap> overlap_by_condition;
  std::map<int, train::MaskOverlap> overlap_by_age;
  bool keep = false;
  std::string source;  // the name the kept poses carry

  void keep_pose(const Pose& p, bool dancer, const camera::sim::Joints13* label, const std::uint8_t* label_valid) {
    if (!keep) return;
    ScoredPose s;
    s.source = source;
    s.dancer = dancer;
    s.pose = p;
    if (label)
      for (int j = 0; j < 13; ++j) {
        s.truth[std::size_t(j)] = {(*label)[std::size_t(j)].x(), (*label)[std::size_t(j)].y(), (*label)[std::size_t(j)].z()};
        s.valid[std::size_t(j)] = label_valid[j];
      }
    r.poses.push_back(std::move(s));
  }

  // The mask stage 1 left for stage 2 at a tick (net size mh x mw, cells of d pixels) against
  // the true mask then (sensor_w wide); nothing when the pipeline has no mask net.
  void add_mask(const std::uint8_t* truth, int sensor_w, const std::vector<float>& in_use, int mh, int mw, int d,
                const std::vector<std::string>& conditions, int age) {
    if (in_use.size() != std::size_t(mw) * std::size_t(mh)) return;
    train::MaskOverlap o;
    train::add_mask_overlap(o, truth, sensor_w, in_use.data(), mh, mw, d);
    overlap += o;
    for (const std::string& c : conditions) overlap_by_condition[c] += o;
    overlap_by_age[age] += o;
    ++r.mask_iou_by_age[age].ticks;
    ++r.mask_ticks;
  }

  // A pose of a recording or scene with nobody in it: only its verdict counts.
  void add_empty(const Pose& p) {
    ++r.empty_poses;
    r.empty_called_person += p.person;
    keep_pose(p, false, nullptr, nullptr);
  }

  // A pose of a recording with a dancer, against the label at its time.
  void add(const Pose& p, const camera::sim::Joints13& label, const std::array<std::uint8_t, camera::sim::kJointCount>& label_valid,
           bool dancer_shows) {
    const bool dancer_seen = std::any_of(label_valid.begin(), label_valid.end(), [](auto v) { return bool(v); });
    if (dancer_seen && !dancer_shows) {
      ++r.dancer_hidden;
      r.dancer_hidden_called += p.person;
    }
    keep_pose(p, true, &label, label_valid.data());
    if (!p.person) {
      r.person_missed += dancer_seen;
      return;  // no joints: scored as a miss, not as NaN
    }
    r.person_found += dancer_seen;
    train::Pose13 truth, as_run, rescaled;
    std::array<std::uint8_t, train::kJoints> valid{};
    const double z_true = label[0].z();
    // The paper protocol: the prediction scaled to the true head depth (joints scale
    // linearly with the depth they were denormalised with).
    const double k = p.head_depth_mm > 0 && z_true > 1 ? z_true / p.head_depth_mm : 0;
    for (int j = 0; j < train::kJoints; ++j) {
      truth[j] = {label[j].x(), label[j].y(), label[j].z()};
      valid[j] = label_valid[j] && k > 0;
      for (int c = 0; c < 3; ++c) {
        as_run[j][c] = p.joints_mm[j][c];
        rescaled[j][c] = p.joints_mm[j][c] * k;
      }
    }
    if (k > 0 && label_valid[0]) {
      depth_ratio.push_back(p.head_depth_mm / z_true);
      depth_abs += std::abs(p.head_depth_mm - z_true);
    }
    paper.add(rescaled, truth, valid);
    deployed.add(as_run, truth, valid);
    ++r.poses_scored;
  }

  void add_run(const RunStats& st) {
    r.ticks += st.ticks;
    r.mask_runs += st.mask_runs;
    r.mirror_runs += st.mirror_runs;
    r.stale += st.stale;
    crops.crop_area += st.crop_area;
    crops.crop_runs += st.crop_runs;
    crops.mask_crop_area += st.mask_crop_area;
    crops.mask_crop_runs += st.mask_crop_runs;
    tick_ms += total(st.times.tick_ms);
    tore_ms += total(st.times.tore_ms);
    s1_ms += total(st.times.stage1_ms);
    s2_ms += total(st.times.stage2_ms);
  }

  StreamEvalResult result() {
    r.paper = paper.scores();
    r.deployed = deployed.scores();
    const double timed = double(std::max<std::uint64_t>(1, r.ticks - r.stale));  // stale ticks run no stage
    r.mask_run_fraction = double(r.mask_runs) / timed;
    r.mirror_run_fraction = double(r.mirror_runs) / timed;
    r.ms_per_tick = tick_ms / timed;
    r.tore_ms = tore_ms / timed;
    r.stage1_ms = s1_ms / timed;
    r.stage2_ms = s2_ms / timed;
    r.crop_share = crop_share(crops);
    r.mask_crop_runs = crops.mask_crop_runs;
    r.mask_crop_share = crops.mask_crop_runs ? crops.mask_crop_area / double(crops.mask_crop_runs) : 1.0;
    if (r.mask_ticks && overlap.uni > 0) {
      r.mask_iou = overlap.iou();
      r.mask_iou_px = overlap.iou_px();
      r.mask_iou_by_condition = train::measured_iou(overlap_by_condition);
      r.mask_iou_px_by_condition = train::measured_iou(overlap_by_condition, true);
      for (const auto& [age, o] : overlap_by_age) r.mask_iou_by_age[age].iou = o.iou();
    }
    if (!depth_ratio.empty()) {
      r.depth_ratio_median = percentile(depth_ratio, 0.5);
      r.depth_abs_error_mm = depth_abs / double(depth_ratio.size());
    }
    return r;
  }
};

}  // namespace

StreamEvalResult evaluate_stream(const std::string& weights, const std::vector<SimulatedScene>& scenes, const RunOptions& run,
                                 bool keep_poses) {
  namespace sim = camera::sim;
  using Clock = std::chrono::steady_clock;
  StreamScorer sc;
  sc.keep = keep_poses;
  RunOptions opt = run;
  // Ticks on the scene's label and mask clock (as recordings on disk run): each mask stage 2
  // reads is scored against the true mask of its own instant.
  if (!opt.tick_origin_us) opt.tick_origin_us = 0;
  for (const SimulatedScene& scene : scenes) {
    sc.source = scene.sim->spec().name;
    const sim::Simulator& simulator = *scene.sim;
    const double end_s = simulator.duration_s();
    const int W = simulator.camera().width;
    PosePipeline pipe(weights, W, simulator.camera().height, opt);
    sc.r.stage1_bf16 = pipe.stage1_bf16();
    sc.r.stage1_precision = pipe.stage1_precision();
    sc.r.stage2_bf16 = pipe.stage2_bf16();
    sc.r.mask_max_age = pipe.mask_max_age();
    const int d = pipe.mask_downscale(), mw = W / d, mh = simulator.camera().height / d;
    const std::vector<std::string> conditions = conditions_in(sc.source);
    const std::int64_t scored_from = std::llround(scene.warmup_s * 1e6), scored_to = std::llround(end_s * 1e6);
    std::vector<std::uint8_t> truth;
    std::vector<Pose> poses;
    const auto keep = [&](const Pose& p) {
      // Whole microseconds (as the masks' span): the tick at the warm-up's end is scored.
      if (p.t_us < scored_from || p.t_us > scored_to) return;
      poses.push_back(p);
      // The mask in use is only readable inside the callback.
      if (scene.mask_bits.empty() || !pipe.masks_are_for(p)) return;
      const auto at = mask_index_near(scene.mask_t, 0, scene.mask_t.size(), p.t_us);
      if (!at || !scene.true_mask(*at, truth)) return;
      sc.add_mask(truth.data(), W, pipe.last_stage1_mask(), mh, mw, d, conditions, p.mask_age);
    };
    const auto t0 = Clock::now();
    pipe.push(scene.events, keep);
    pipe.finish(std::llround(end_s * 1e6), keep);
    sc.r.wall_s += std::chrono::duration<double>(Clock::now() - t0).count();
    for (const Pose& p : poses) {
      const double t = double(p.t_us) * 1e-6;
      const bool dancer = simulator.spec().dancer;
      count_by_condition(sc.r.presence_by_condition, sc.source, dancer, p.person);
      if (!dancer) {  // an `-empty` scene
        sc.add_empty(p);
        continue;
      }
      const sim::Label l = simulator.label_at(t);
      sc.add(p, l.joints_mm, l.valid, shows_at(scene.mask_t, scene.dancer_shows, p.t_us));
    }
    sc.add_run(pipe.stats());
  }
  return sc.result();
}

StreamEvalResult evaluate_recordings(const std::string& weights, const std::vector<std::string>& recordings, double seconds,
                                     double skip_s, const RunOptions& run, std::ostream& progress, bool keep_poses) {
  namespace sim = camera::sim;
  StreamScorer sc;
  sc.keep = keep_poses;
  RunOptions opt = run;
  opt.tick_origin_us = 0;
  for (std::size_t i = 0; i < recordings.size(); ++i) {
    const sim::RecordingInfo info = sim::read_recording_info(recordings[i]);
    sc.source = info.name;
    PosePipeline pipe(weights, info.camera.width, info.camera.height, opt);
    sc.r.stage1_bf16 = pipe.stage1_bf16();
    sc.r.stage1_precision = pipe.stage1_precision();
    sc.r.stage2_bf16 = pipe.stage2_bf16();
    sc.r.mask_max_age = pipe.mask_max_age();
    const std::int64_t end_us = info.first_event_us + std::llround(seconds * 1e6);
    const std::int64_t skip_us = info.first_event_us + std::llround(skip_s * 1e6);
    std::optional<TrueMasks> truth;
    if (info.dancer) truth.emplace(recordings[i], std::max(0.0, seconds - skip_s), skip_s);
    const int d = pipe.mask_downscale(), mw = info.camera.width / d, mh = info.camera.height / d;
    const std::vector<std::string> conditions = conditions_in(info.name);
    std::vector<Pose> poses;
    const auto keep = [&](const Pose& p) {
      if (p.t_us < skip_us || p.t_us > end_us) return;
      poses.push_back(p);
      if (!truth || !pipe.masks_are_for(p)) return;
      if (const auto at = truth->index_at(p.t_us))
        sc.add_mask(truth->mask(*at), info.camera.width, pipe.last_stage1_mask(), mh, mw, d, conditions, p.mask_age);
    };
    sc.r.wall_s += run_file(pipe, recordings[i], end_us, keep);
    sim::Joints13 joints;
    std::array<std::uint8_t, sim::kJointCount> valid{};
    std::uint64_t called = 0;
    for (const Pose& p : poses) {
      count_by_condition(sc.r.presence_by_condition, info.name, info.dancer, p.person);
      called += p.person;
      if (!info.dancer) {
        sc.add_empty(p);
        continue;
      }
      sim::label_at(info, p.t_us, joints, valid);
      sc.add(p, joints, valid, truth->shows_at(p.t_us));
    }
    sc.add_run(pipe.stats());
    progress << "  [" << (i + 1) << "/" << recordings.size() << "] " << info.name << (info.dancer ? "" : " (empty)") << ": "
             << poses.size() << " poses, " << called << " said person\n";
  }
  return sc.result();
}

std::string scored_poses_csv(const std::vector<ScoredPose>& poses) {
  std::ostringstream o;
  o << "source,t_us,dancer,person,confidence,mask_ran,head_depth_mm,true_head_depth_mm";
  for (const char* what : {"", "true_"})
    for (int j = 0; j < 13; ++j)
      for (const char* c : {"x", "y", "z"}) o << ',' << what << 'j' << j << '_' << c;
  for (int j = 0; j < 13; ++j) o << ",valid" << j;
  o << ",mask_age\n";
  o << std::setprecision(7);
  for (const ScoredPose& s : poses) {
    const Pose& p = s.pose;
    o << s.source << ',' << p.t_us << ',' << int(s.dancer) << ',' << int(p.person) << ',' << p.confidence << ','
      << int(p.mask_ran) << ',' << p.head_depth_mm << ',';
    if (s.dancer) o << s.truth[0][2];
    for (const auto& jt : p.joints_mm)
      for (float v : jt) {
        o << ',';
        if (p.person) o << v;
      }
    for (const auto& jt : s.truth)
      for (double v : jt) {
        o << ',';
        if (s.dancer) o << v;
      }
    for (std::uint8_t v : s.valid) o << ',' << int(v);
    o << ',' << p.mask_age << '\n';
  }
  return o.str();
}

}  // namespace yelan::run
