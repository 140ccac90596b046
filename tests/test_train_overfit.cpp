// The whole path from labels to loss can learn: a small pose net trained on one short
// recording must fit it (training MPJPE under 40 mm). If this fails, something between the
// simulator's labels, the windows, the batch, the normalisation, the loss and the optimiser
// is broken, whatever the other tests say.
#include <catch2/catch.hpp>

#include <filesystem>
#include <sstream>
#include <unistd.h>

#include "camera/sim/presets.h"
#include "camera/sim/simulator.h"
#include "engine/model_config.h"
#include "engine/threads.h"
#include "engine/train/trainer.h"

namespace sim = yelan::camera::sim;

TEST_CASE("train: a small pose net overfits one short recording below 40 mm MPJPE", "[train]") {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("yelan-overfit-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  // A small sensor keeps the simulation and the net cheap; the geometry is the DAVIS346's
  // field of view.
  sim::SimSpec s = sim::preset_spec("ben-dance3-front-high-static");
  s.duration_s = 1.0;
  s.scene.intrinsics.width = 128, s.scene.intrinsics.height = 96;
  s.scene.intrinsics.fx = s.scene.intrinsics.fy = 485.0 * 128 / 346;
  s.scene.intrinsics.cx = 64, s.scene.intrinsics.cy = 48;
  const std::string rec = (dir / "one.yelan.h5").string();
  sim::write_recording(s, rec);

  yelan::train::TrainSpec t;
  t.stage = "pose";
  t.cfg = yelan::parse_model_config(R"({"name": "overfit", "input": {"channels": 6, "sensor_height": 96,
      "sensor_width": 128, "downscale": 1, "window": 4}, "mask": {"width_mult": 0.125, "n_masks": 2},
      "pose": {"width_mult": 0.25, "hidden": 8, "stages": 1, "joints": 13, "convlstm": "causal"}})",
                                    "overfit config");
  t.data = {rec};
  t.val_data = {rec};  // on purpose: the score is the training fit
  t.batch = 4;
  t.steps = 600;
  t.steps_per_epoch = 100;
  t.val_windows = 12;
  t.patience = 100;
  t.adam.lr = 2e-3;
  t.warmup_steps = 20;
  t.checkpoint_minutes = 1000;
  t.out_dir = (dir / "run").string();
  std::ostringstream log;
  // One thread: ctest runs two tests at once on two cores, and OpenMP threads that outnumber
  // the cores spin against each other (this test took 10 minutes that way, 1 alone).
  const int saved = yelan::threads();
  yelan::set_threads(1);
  const yelan::train::TrainResult r = yelan::train::train(t, log);
  yelan::set_threads(saved);
  INFO(log.str());
  CHECK(r.steps == t.steps);
  CHECK(r.best_val < 40.0);  // mm: the pose stage keeps its best validation MPJPE
  std::filesystem::remove_all(dir);
}
