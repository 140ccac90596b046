// One input path: the batch the trainer builds for a window of a recording equals, value
// for value, what `yelan run` feeds stage 2 at the same instants of the same recording (the
// TORE of every event so far, downscaled, masked by stage 1's own current mask).
#include <catch2/catch.hpp>

#include <cstring>

#include "camera/io/event_reader.h"
#include "camera/sim/presets.h"
#include "camera/sim/recording_windows.h"
#include "cli_util.h"
#include "engine/run/pipeline.h"
#include "engine/train/batch.h"
#include "weights_tools/network_io.h"
#include "weights_tools/weights_file.h"

namespace sim = yelan::camera::sim;

TEST_CASE("input path: the trainer's batch equals yelan run's stage-2 input at the same instant", "[run]") {
  yelan::test::CliTempDir d("input-path");
  const std::string rec = d / "one.yelan.h5", w = d / "w.h5";
  sim::SimSpec s = sim::preset_spec("ben-dance3-front-high-dynamic");
  s.duration_s = 0.9;
  sim::write_recording(s, rec);
  const auto init = yelan::test::run_cli({"weights", "init", "--config", "micro", "-o", w, "--seed", "4"});
  INFO(init.err);
  REQUIRE(init.code == 0);

  // The trainer's side: consecutive windows with the full history, behind the frozen mask net.
  yelan::weights::LoadedNetworks nets(yelan::weights::load_weights(w), w);
  const yelan::ModelConfig& cfg = nets.cfg;
  nets.mask.set_training(false);
  sim::WindowStreamOptions o;
  o.window = cfg.window;
  o.history_s = 5;
  sim::RecordingWindowStream stream({rec}, 1, o);
  sim::SimWindow win;
  for (int k = 0; k < 12; ++k) stream.next(win);  // well into the recording
  yelan::train::BatchBuilder builder(cfg, 1, yelan::train::MaskSource::net);
  builder.add(win, nets.mask, nullptr);
  const yelan::layers::Act& batch = builder.batch().input.act;

  // `yelan run`'s side: ticks on the recording's frame times, stage 1 on every tick.
  yelan::run::RunOptions ro;
  ro.beta = 2;
  ro.tick_origin_us = 0;
  ro.crop_margin = 0;
  ro.skip_empty = false;
  yelan::run::PosePipeline pipe(w, 346, 260, ro);
  auto reader = yelan::camera::open_event_file(rec);
  std::vector<yelan::camera::Event> ev;
  int matched = 0;
  const std::size_t per_frame = std::size_t(batch.cb()) * batch.pixels() * 16;
  auto on_pose = [&](const yelan::run::Pose& p) {
    for (int t = 0; t < cfg.window; ++t) {
      if (p.t_us != win.frames[std::size_t(t)].t_us) continue;
      const yelan::layers::Act& in = pipe.last_input();
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
  CHECK(matched == cfg.window);
  // And the input is not trivially equal: the mask cut something and kept something.
  double sum = 0;
  for (std::size_t i = 0; i < per_frame; ++i) sum += batch.data[i];
  CHECK(sum > 0);
}
