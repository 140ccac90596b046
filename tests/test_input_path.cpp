// One input path: the batch the trainer builds for a window of a recording equals, value
// for value, what `yelan run` feeds stage 2 at the same instants of the same recording (the
// TORE of every event so far, downscaled, masked by stage 1's own current mask).
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <memory>
#include <set>
#include <utility>

#include "camera/io/event_reader.h"
#include "camera/sim/presets.h"
#include "camera/sim/recording_windows.h"
#include "cli_util.h"
#include "engine/run/pipeline.h"
#include "engine/train/batch.h"
#include "weights_tools/network_io.h"
#include "weights_tools/weights_file.h"

namespace sim = yelan::camera::sim;

namespace {

// A 0.9 s recording and a micro model with a random mask net, in eval mode.
struct RecordingFixture {
  yelan::test::CliTempDir d{"input-path"};
  std::string rec = d / "one.yelan.h5", w = d / "w.h5";
  std::unique_ptr<yelan::weights::LoadedNetworks> nets;
  RecordingFixture() {
    sim::SimSpec s = sim::preset_spec("ben-dance3-front-high-dynamic");
    s.duration_s = 0.9;
    sim::write_recording(s, rec);
    const auto init = yelan::test::run_cli({"weights", "init", "--config", "micro", "-o", w, "--seed", "4"});
    INFO(init.err);
    REQUIRE(init.code == 0);
    nets = std::make_unique<yelan::weights::LoadedNetworks>(yelan::weights::load_weights(w), w);
    nets->mask.set_training(false);
  }
  // Window k of the recording, `lead` frames before the config's window.
  sim::SimWindow window(int k, int lead) {
    sim::WindowStreamOptions o;
    o.window = lead + nets->cfg.window;
    o.history_s = 5;
    sim::RecordingWindowStream stream({rec}, 1, o);
    sim::SimWindow win;
    for (int i = 0; i <= k; ++i) stream.next(win);
    return win;
  }
  // The q-quantile of mask `channel`'s probabilities on `frame` of `win`: a cut that keeps
  // part of the picture (a random net's masks all keep everything at the usual cut).
  float quantile_cut(const sim::SimWindow& win, int frame, int channel, double q) {
    const yelan::ModelConfig& cfg = nets->cfg;
    yelan::layers::ActBuf one;
    one.resize(1, cfg.channels, cfg.height(), cfg.width());
    yelan::input::downscale_tore(win.frames[std::size_t(frame)].tore, cfg.sensor_height, cfg.sensor_width, cfg.downscale,
                                 one.act, 0);
    yelan::layers::NoGrad no_grad;
    nets->mask.forward(one.act);
    const yelan::layers::Act& m = nets->mask.masks();
    std::vector<float> p(m.pixels());
    for (std::size_t i = 0; i < p.size(); ++i) p[i] = 1 / (1 + std::exp(-m.data[i * 16 + channel]));
    const std::size_t at = std::size_t(q * double(p.size()));
    std::nth_element(p.begin(), p.begin() + at, p.end());
    return p[at];
  }
};

// Against input `before`, how many values of `after` that `before` kept changed (a grown mask
// must keep them as they were), and how many `before` zeroed are kept.
std::pair<std::size_t, std::size_t> lost_and_gained(const std::vector<float>& before, const std::vector<float>& after) {
  std::size_t lost = 0, gained = 0;
  for (std::size_t i = 0; i < before.size(); ++i) {
    lost += before[i] != 0 && after[i] != before[i];
    gained += before[i] == 0 && after[i] != 0;
  }
  return {lost, gained};
}

// `yelan run` over the recording, its stage-2 input at each of the window's S frame times
// checked against that frame of `batch`, value for value; returns how many frames it met.
int frames_matching(const std::string& w, const std::string& rec, const yelan::run::RunOptions& ro, const sim::SimWindow& win,
                    int S, const yelan::layers::Act& batch) {
  yelan::run::PosePipeline pipe(w, 346, 260, ro);
  auto reader = yelan::camera::open_event_file(rec);
  std::vector<yelan::camera::Event> ev;
  int matched = 0;
  const std::size_t per_frame = std::size_t(batch.cb()) * batch.pixels() * 16;
  auto on_pose = [&](const yelan::run::Pose& p) {
    for (int t = 0; t < S; ++t) {
      if (p.t_us != win.frames[std::size_t(t)].t_us) continue;
      const yelan::layers::Act& in = pipe.last_input();
      REQUIRE(in.c == batch.c);
      REQUIRE(std::size_t(in.cb()) * in.pixels() * 16 == per_frame);
      INFO("frame " << t << " at " << p.t_us << " us");
      CHECK(std::memcmp(in.data, batch.data + std::size_t(t) * per_frame, per_frame * sizeof(float)) == 0);
      ++matched;
    }
  };
  while (reader->read(ev, 1 << 15) > 0) {
    pipe.push(ev, on_pose);
    ev.clear();
  }
  return matched;
}

}  // namespace

TEST_CASE("input path: the trainer's batch equals yelan run's stage-2 input at the same instant", "[run]") {
  RecordingFixture fx;
  const std::string &w = fx.w, &rec = fx.rec;
  const sim::SimWindow win = fx.window(11, 0);  // well into the recording
  // As the model cuts its masks, and with them grown (run.mask_grow).
  for (const int grow : {0, 3}) {
    INFO("run.mask_grow " << grow);
    // The trainer's side: consecutive windows with the full history, behind the frozen mask net.
    yelan::ModelConfig cfg = fx.nets->cfg;
    cfg.mask_grow = grow;
    if (grow) cfg.mask_cut = fx.quantile_cut(win, cfg.window - 1, 0, 0.7);  // a mask with something to grow into
    yelan::train::BatchBuilder builder(cfg, 1, yelan::train::MaskSource::net);
    builder.add(win, fx.nets->mask, nullptr);
    const yelan::layers::Act& batch = builder.batch().input.act;

    // `yelan run`'s side: ticks on the recording's frame times, stage 1 on every tick.
    yelan::run::RunOptions ro;
    ro.beta = 2;
    ro.tick_origin_us = 0;
    ro.crop_margin = 0;
    ro.skip_empty = false;
    ro.mask_grow = grow;
    if (grow) ro.mask_cut = cfg.mask_cut;
    CHECK(frames_matching(w, rec, ro, win, cfg.window, batch) == cfg.window);
    const std::size_t per_frame = std::size_t(batch.cb()) * batch.pixels() * 16;
    // And the input is not trivially equal: the mask cut something and kept something.
    double sum = 0;
    for (std::size_t i = 0; i < per_frame; ++i) sum += batch.data[i];
    CHECK(sum > 0);
    // Grown, the mask keeps all the same cut kept ungrown, and more.
    if (grow == 0) continue;
    const std::vector<float> now(batch.data, batch.data + std::size_t(cfg.window) * per_frame);
    cfg.mask_grow = 0;
    yelan::train::BatchBuilder same_cut(cfg, 1, yelan::train::MaskSource::net);
    same_cut.add(win, fx.nets->mask, nullptr);
    const yelan::layers::Act& ungrown = same_cut.batch().input.act;
    const auto [lost, more] = lost_and_gained({ungrown.data, ungrown.data + now.size()}, now);
    CHECK(lost == 0);
    CHECK(more > 0);
  }
}

TEST_CASE("run.mask_grow: the true masks a trainer reads grow too; the config refuses a bad value", "[run]") {
  RecordingFixture fx;
  const sim::SimWindow win = fx.window(11, 0);
  yelan::ModelConfig cfg = fx.nets->cfg;
  std::vector<std::vector<float>> kept;
  for (const int grow : {0, 2}) {
    cfg.mask_grow = grow;
    yelan::train::BatchBuilder b(cfg, 1, yelan::train::MaskSource::truth);
    b.add(win, fx.nets->mask, nullptr);
    const auto& in = b.batch().input.act;
    kept.emplace_back(in.data, in.data + in.floats());
  }
  const auto [lost, more] = lost_and_gained(kept[0], kept[1]);
  CHECK(lost == 0);
  CHECK(more > 0);
  // micro has no run section: one with the key alone.
  const std::string text = fx.nets->cfg.json;
  REQUIRE(text.find("\"run\"") == std::string::npos);
  const auto with = [&](const std::string& value) {
    return text.substr(0, text.rfind('}')) + ", \"run\": {\"mask_grow\": " + value + "}}";
  };
  CHECK(yelan::parse_model_config(text, "micro").mask_grow == 0);
  CHECK(yelan::parse_model_config(with("2"), "grow").mask_grow == 2);
  CHECK_THROWS_AS(yelan::parse_model_config(with("-1"), "grow"), yelan::ConfigError);
  CHECK_THROWS_AS(yelan::parse_model_config(with("65"), "grow"), yelan::ConfigError);
}


TEST_CASE("mask reuse: each frame behind the future mask of stage 1's latest run, as early exit", "[run]") {
  RecordingFixture fx;
  yelan::ModelConfig cfg = fx.nets->cfg;
  const int S = cfg.window, d = cfg.downscale, lead = 4;
  REQUIRE(cfg.n_masks >= 3);
  REQUIRE(S >= 2);
  const int sh = cfg.sensor_height, sw = cfg.sensor_width;
  const sim::SimWindow win = fx.window(6, lead);
  yelan::layers::ActBuf one, expect;
  one.resize(1, cfg.channels, cfg.height(), cfg.width());
  expect.resize(1, cfg.channels, cfg.height(), cfg.width());
  // Cut at the median probability of a future mask, so that masks of other ages differ; the
  // reused future masks at their own cut, lower (run.mask_cut_reused).
  cfg.mask_cut = fx.quantile_cut(win, lead, 1, 0.5);
  cfg.mask_cut_reused = fx.quantile_cut(win, lead, 1, 0.25);
  std::vector<float> keep, fresh_keep;
  int ages_seen = 0;
  bool some_mask_differs = false;
  std::size_t per_frame = 0;
  // {2, 1}: runs at frames -1, 1, ...; {3, 2}: at -2, 1, ...; {3, 1}: at -1, 2, ...
  for (const yelan::train::MaskReuse reuse : {yelan::train::MaskReuse{2, 1}, {3, 2}, {3, 1}}) {
    yelan::train::BatchBuilder builder(cfg, 1, yelan::train::MaskSource::net, lead);
    builder.add(win, fx.nets->mask, nullptr, nullptr, false, &reuse);
    const yelan::layers::Act& got = builder.batch().input.act;
    per_frame = std::size_t(got.cb()) * got.pixels() * 16;
    // By hand: stage 1 on frame t - age alone, its mask `age` cut where the config cuts
    // (the current mask at run.mask_cut, a future one at run.mask_cut_reused).
    for (int t = 0; t < S; ++t) {
      const int age = (t + reuse.phase) % reuse.period;
      INFO("period " << reuse.period << ", phase " << reuse.phase << ": frame " << t << ", mask age " << age);
      const auto& f = win.frames[std::size_t(lead + t - age)];
      yelan::input::downscale_tore(f.tore, sh, sw, d, one.act, 0);
      yelan::layers::NoGrad no_grad;
      fx.nets->mask.forward(one.act);
      yelan::input::mask_cut(fx.nets->mask.masks(), 0, age, keep, float(age ? cfg.reused_mask_cut() : cfg.mask_cut));
      yelan::input::mask_cut(fx.nets->mask.masks(), 0, 0, fresh_keep, float(cfg.mask_cut));
      if (age > 0) some_mask_differs |= keep != fresh_keep;
      ages_seen |= 1 << age;
      const auto& g = win.frames[std::size_t(lead + t)];
      yelan::input::downscale_tore(g.tore, sh, sw, d, expect.act, 0);
      yelan::input::apply_mask(expect.act, 0, keep);
      CHECK(std::memcmp(expect.act.data, got.data + std::size_t(t) * per_frame, per_frame * sizeof(float)) == 0);
    }
  }
  CHECK(ages_seen == 7);
  CHECK(some_mask_differs);  // else reading the current mask would pass as well

  // Every frame a fresh run: the path without reuse, value for value (its windows lead 0).
  const yelan::train::MaskReuse every{1, 0};
  yelan::train::BatchBuilder a(cfg, 1, yelan::train::MaskSource::net, lead), b(cfg, 1, yelan::train::MaskSource::net);
  a.add(win, fx.nets->mask, nullptr, nullptr, false, &every);
  const sim::SimWindow plain = fx.window(6, 0);
  REQUIRE(plain.frames[0].t_us != win.frames[std::size_t(lead)].t_us);  // the stream draws windows by their length
  sim::SimWindow cut = win;
  cut.frames.erase(cut.frames.begin(), cut.frames.begin() + lead);
  b.add(cut, fx.nets->mask, nullptr);
  CHECK(std::memcmp(a.batch().input.act.data, b.batch().input.act.data, S * per_frame * sizeof(float)) == 0);

  // A phase beyond the window's lead, a period beyond the future masks: refused.
  yelan::train::BatchBuilder c(cfg, 1, yelan::train::MaskSource::net, lead);
  const yelan::train::MaskReuse far{lead + 2, lead + 1}, long_period{cfg.n_masks + 1, 0};
  CHECK_THROWS_AS(c.add(win, fx.nets->mask, nullptr, nullptr, false, &far), std::invalid_argument);
  CHECK_THROWS_AS(c.add(win, fx.nets->mask, nullptr, nullptr, false, &long_period), std::invalid_argument);
}

TEST_CASE("mask reuse: periods drawn over 1..N, phases below the period", "[run]") {
  sim::Rng r(7, 1);
  std::set<std::pair<int, int>> seen;
  for (int i = 0; i < 2000; ++i) {
    const auto m = yelan::train::draw_mask_reuse(r, 4);
    REQUIRE(m.period >= 1);
    REQUIRE(m.period <= 4);
    REQUIRE(m.phase >= 0);
    REQUIRE(m.phase < m.period);
    seen.insert({m.period, m.phase});
  }
  CHECK(seen.size() == 10);  // 1 + 2 + 3 + 4 (period, phase) pairs
  CHECK_THROWS_AS(yelan::train::draw_mask_reuse(r, 0), std::invalid_argument);
}

namespace {

// micro with pose.outside_input (and a crop margin), initialised with the fixture's seed (the
// same mask net: its architecture is micro's).
std::string outside_weights(RecordingFixture& fx, int crop_margin) {
  std::string text = fx.nets->cfg.json;
  const std::size_t at = text.find("\"convlstm\": \"causal\"");
  REQUIRE(at != std::string::npos);
  text.insert(at, "\"outside_input\": true, \"crop_margin\": " + std::to_string(crop_margin) + ", ");
  const std::string cfg_path = fx.d / ("outside" + std::to_string(crop_margin) + ".json");
  const std::string w = fx.d / ("outside" + std::to_string(crop_margin) + ".h5");
  std::ofstream(cfg_path) << text;
  const auto init = yelan::test::run_cli({"weights", "init", "--config", cfg_path, "-o", w, "--seed", "4"});
  INFO(init.err);
  REQUIRE(init.code == 0);
  return w;
}

// Every stage-2 input `yelan run` builds on the recording, one vector a tick.
std::vector<std::vector<float>> run_inputs(const std::string& w, const std::string& rec, const yelan::run::RunOptions& ro,
                                           std::uint64_t* box_ticks = nullptr) {
  yelan::run::PosePipeline pipe(w, 346, 260, ro);
  auto reader = yelan::camera::open_event_file(rec);
  std::vector<yelan::camera::Event> ev;
  std::vector<std::vector<float>> inputs;
  auto on_pose = [&](const yelan::run::Pose&) {
    const yelan::layers::Act& in = pipe.last_input();
    inputs.emplace_back(in.data, in.data + std::size_t(in.cb()) * in.pixels() * 16);
  };
  while (reader->read(ev, 1 << 15) > 0) {
    pipe.push(ev, on_pose);
    ev.clear();
  }
  if (box_ticks) *box_ticks = pipe.stats().tore_box_ticks;
  return inputs;
}

}  // namespace

TEST_CASE("pose.outside_input: inside and outside the true mask, the outside part ending at the crop", "[run]") {
  RecordingFixture fx;
  const sim::SimWindow win = fx.window(11, 0);
  for (const int margin : {0, 3}) {
    INFO("crop margin " << margin);
    const std::string w = outside_weights(fx, margin);
    const yelan::ModelConfig cfg = yelan::weights::LoadedNetworks(yelan::weights::load_weights(w), w).cfg;
    REQUIRE(cfg.pose_channels() == 2 * cfg.channels);
    yelan::train::BatchBuilder builder(cfg, 1, yelan::train::MaskSource::truth);
    builder.add(win, fx.nets->mask, nullptr);
    const yelan::layers::Act& batch = builder.batch().input.act;
    REQUIRE(batch.c == 2 * cfg.channels);
    const std::size_t per_frame = std::size_t(batch.cb()) * batch.pixels() * 16;
    // By hand: inside = TORE x mask, outside = TORE x (1 - mask) in the mask's box grown by
    // the margin (the whole frame at 0), zero elsewhere; a cell is the dancer's when any of
    // its sensor pixels is.
    const int t = cfg.window - 1, W = cfg.width(), H = cfg.height(), d = cfg.downscale;
    yelan::layers::ActBuf one;
    one.resize(1, cfg.channels, H, W);
    const auto& f = win.frames[std::size_t(t)];
    yelan::input::downscale_tore(f.tore, cfg.sensor_height, cfg.sensor_width, d, one.act, 0);
    std::vector<float> keep(std::size_t(H) * W, 0.f);
    int x0 = W, y0 = H, x1 = 0, y1 = 0;
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x)
        for (int dy = 0; dy < d; ++dy)
          for (int dx = 0; dx < d; ++dx)
            if (f.mask[std::size_t(y * d + dy) * cfg.sensor_width + x * d + dx]) {
              keep[std::size_t(y) * W + x] = 1;
              x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x + 1), y1 = std::max(y1, y + 1);
            }
    REQUIRE(x1 > 0);
    std::size_t inside_kept = 0, outside_kept = 0, beyond = 0;
    for (int y = 0; y < H; ++y)
      for (int x = 0; x < W; ++x) {
        const std::size_t p = std::size_t(y) * W + x;
        const bool region = margin == 0 || (x >= x0 - margin && x < x1 + margin && y >= y0 - margin && y < y1 + margin);
        beyond += !region;
        const float* got = batch.data + std::size_t(t) * per_frame + p * 16;
        for (int c = 0; c < cfg.channels; ++c) {
          const float v = one.act.data[p * 16 + c], k = keep[p];
          REQUIRE(got[c] == v * k);
          REQUIRE(got[cfg.channels + c] == (region ? v * (1 - k) : 0.f));
          inside_kept += k == 1 && v != 0;
          outside_kept += region && k == 0 && v != 0;
        }
      }
    CHECK(inside_kept > 0);
    CHECK(outside_kept > 0);                // the outside part holds events
    CHECK((margin == 0) == (beyond == 0));  // and, with a margin, ends at the crop
  }
}

TEST_CASE("pose.outside_input: the trainer's batch equals yelan run's input; reading the TORE in the box changes nothing", "[run]") {
  RecordingFixture fx;
  const sim::SimWindow win = fx.window(11, 0);
  for (const int margin : {0, 3}) {
    INFO("crop margin " << margin);
    const std::string w = outside_weights(fx, margin);
    yelan::ModelConfig cfg = yelan::weights::LoadedNetworks(yelan::weights::load_weights(w), w).cfg;
    cfg.mask_cut = fx.quantile_cut(win, cfg.window - 1, 0, 0.8);  // the mask net is the fixture's (same seed)
    yelan::train::BatchBuilder builder(cfg, 1, yelan::train::MaskSource::net);
    builder.add(win, fx.nets->mask, nullptr);
    const yelan::layers::Act& batch = builder.batch().input.act;
    REQUIRE(batch.c == 2 * cfg.channels);
    yelan::run::RunOptions ro;
    ro.beta = 2;  // stage 1 on every tick, as the builder's fresh masks
    ro.tick_origin_us = 0;
    ro.skip_empty = false;
    ro.mask_cut = cfg.mask_cut;
    CHECK(frames_matching(w, fx.rec, ro, win, cfg.window, batch) == cfg.window);
  }
  // Early exit with a trained stage 1 (the shipped one, its masks on the dancer alone): stage 2
  // alone reads the TORE in its crop box between stage 1's runs, and its input is on every
  // tick what reading the whole sensor gives (no stale events outside the mask).
  const std::string shipped = std::string(YELAN_SOURCE_DIR) + "/models/default.h5";
  std::string text = yelan::weights::load_weights(shipped).config_json;
  const std::size_t at = text.find("\"convlstm\"");
  REQUIRE(at != std::string::npos);
  text.insert(at, "\"outside_input\": true, ");
  const std::string cfg_path = fx.d / "shipped-outside.json", w = fx.d / "shipped-outside.h5";
  std::ofstream(cfg_path) << text;
  const auto widen = yelan::test::run_cli({"weights", "widen", "--weights", shipped, "--config", cfg_path, "-o", w});
  INFO(widen.err);
  REQUIRE(widen.code == 0);
  yelan::run::RunOptions ro;
  ro.tick_origin_us = 0;
  std::uint64_t box_ticks = 0;
  const auto boxed = run_inputs(w, fx.rec, ro, &box_ticks);
  ro.tore_box = false;
  const auto whole = run_inputs(w, fx.rec, ro);
  REQUIRE(boxed.size() == whole.size());
  CHECK(boxed.size() > 20);
  CHECK(box_ticks > 0);
  std::size_t differing = 0;  // counted: Catch would print millions of floats
  for (std::size_t i = 0; i < boxed.size(); ++i) differing += boxed[i] != whole[i];
  CHECK(differing == 0);
}
