// `yelan train`: the CPU trainer (engine/train) on windows streamed from the simulator or
// read from labelled recordings on disk.
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iostream>

#include "camera/sim/presets.h"
#include "camera/sim/recording_windows.h"
#include "engine/cli/args.h"
#include "engine/cli/cli.h"
#include "engine/cli/handlers.h"
#include "engine/cli/vet_recordings.h"
#include "engine/threads.h"
#include "engine/train/trainer.h"

namespace yelan::cli {

namespace sim = camera::sim;

// "train" / "test" (the grid splits), @FILE (one preset per line, '#' comments: the files
// of benchmarks/splits) or comma-separated preset names (also used by eval).
std::vector<sim::SimSpec> scenes_from(const std::string& text) {
  std::vector<std::string> names;
  if (text == "train" || text == "test") {
    names = sim::grid_presets(text);
  } else if (!text.empty() && text[0] == '@') {
    std::ifstream f(text.substr(1));
    if (!f) throw UsageError("--sim " + text + ": cannot read " + text.substr(1));
    std::string line;
    for (int no = 1; std::getline(f, line); ++no) {
      const auto a = line.find_first_not_of(" \t\r"), b = line.find_last_not_of(" \t\r");
      if (a == std::string::npos || line[a] == '#') continue;
      const std::string n = line.substr(a, b - a + 1);
      try {
        sim::preset_spec(n);
      } catch (const std::exception& e) {
        throw UsageError(text.substr(1) + ":" + std::to_string(no) + ": " + e.what());
      }
      names.push_back(n);
    }
  } else {
    names = split_list(text);
  }
  if (names.empty()) throw UsageError("--sim: no scenes in '" + text + "'");
  std::vector<sim::SimSpec> out;
  for (const auto& n : names) out.push_back(sim::preset_spec(n));
  return out;
}

int cmd_train(const std::vector<std::string>& argv, std::ostream& out, std::ostream& err) {
  const Args a("train", argv,
               {"--stage", "--config", "--sim", "--val-sim", "--data", "--val-data", "-o", "--steps", "--batch", "--epoch-steps", "--lr",
                "--seed", "--mask-weights", "--init", "--checkpoint-minutes", "--max-minutes", "--max-cpu-minutes", "--threads", "--patience",
                "--val-windows", "--lr-step-epochs", "--lr-schedule", "--warmup-steps", "--history", "--stop-at", "--mask-frames", "--empty-weight", "--dice-weight", "--mask-focus",
                "--windows-per-visit", "--mask-reuse", "--read-threads"},
               {"--occlusion", "--warp", "--flip", "--frame-zoom", "--swap-loss", "--resume", "--quiet", "--validate-start", "--freeze-bn"});
  a.expect_positionals(0, 0);
  const auto stage = a.value("--stage"), config = a.value("--config"), simv = a.value("--sim"), o = a.value("-o");
  const auto data = a.value("--data");
  if (!stage || !config || (!simv && !data) || !o)
    throw UsageError("train needs --stage mask|pose --config NAME|FILE --sim PRESETS|train or --data DIR, and -o OUTDIR");
  if (simv && data) throw UsageError("give --sim or --data, not both");
  if (a.value("--val-data") && !data) throw UsageError("--val-data goes with --data");
  if (a.value("--val-sim") && data) throw UsageError("--val-sim goes with --sim (with --data: --val-data DIR)");
  train::TrainSpec spec;
  spec.stage = *stage;
  if (spec.stage != "mask" && spec.stage != "pose") throw UsageError("--stage must be mask or pose");
  spec.cfg = load_model_config(*config);  // a bad config: cli.cpp's handler, exit 2
  if (const auto t = a.value("--threads")) {
    const auto n = parse_thread_count(*t);
    if (!n) throw UsageError("--threads '" + *t + "': expected 1..1024");
    set_threads(*n);
  }
  if (simv) {
    spec.scenes = scenes_from(*simv);
    if (const auto v = a.value("--val-sim")) spec.val_scenes = scenes_from(*v);
  } else {
    try {
      namespace fs = std::filesystem;
      // A dataset folder (`yelan sim --dataset`): its train/ and val/ splits.
      const bool dataset = !a.value("--val-data") && fs::is_directory(fs::path(*data) / "train") &&
                           fs::is_directory(fs::path(*data) / "val");
      const auto all = camera::sim::list_recordings(dataset ? (fs::path(*data) / "train").string() : *data);
      if (dataset) {
        spec.data = all;
        spec.val_data = camera::sim::list_recordings((fs::path(*data) / "val").string());
      } else if (const auto v = a.value("--val-data")) {
        spec.data = all;
        spec.val_data = camera::sim::list_recordings(*v);
      } else {
        camera::sim::split_by_recording(all, spec.data, spec.val_data);
      }
    } catch (const std::runtime_error& e) {
      throw UsageError(std::string("--data: ") + e.what());
    }
    std::vector<std::string> every = spec.data;
    every.insert(every.end(), spec.val_data.begin(), spec.val_data.end());
    vet_recordings_up_front(every, err);
    if (spec.stage == "pose") {
      // Scenes with nobody in them teach stage 1 "nobody there"; stage 2 has no pose to learn.
      std::size_t dropped = 0;
      for (auto* list : {&spec.data, &spec.val_data}) {
        std::vector<std::string> kept;
        for (const auto& f : *list)
          if (camera::sim::read_recording_info(f).dancer) kept.push_back(f);
        dropped += list->size() - kept.size();
        *list = kept;
      }
      if (dropped) err << dropped << " recordings without a dancer left out (stage 1's negatives)\n";
      if (spec.data.empty() || spec.val_data.empty()) throw UsageError("--data: no recordings with a dancer to train or validate on");
    }
    err << spec.data.size() << " recordings for training, " << spec.val_data.size() << " for validation ("
        << (a.value("--val-data") ? "--val-data" : spec.val_data.size() && spec.val_data[0].find("/val/") != std::string::npos ? "the dataset's val split" : "every tenth by name, split by recording") << ")\n";
  }
  spec.out_dir = *o;
  spec.steps = a.int_value_or("--steps", 1000, 1, 1 << 30);
  spec.batch = a.int_value_or("--batch", 8, 1, 1024);
  spec.stop_at = a.int_value_or("--stop-at", 0, 0, 1 << 30);
  spec.mask_frames = a.int_value_or("--mask-frames", 0, 1, 1 << 10);
  if (spec.mask_frames && spec.stage != "mask") throw UsageError("--mask-frames: for --stage mask only (the pose net's ConvLSTM needs the config's window)");
  spec.steps_per_epoch = a.int_value_or("--epoch-steps", 50, 1, 1 << 30);
  spec.patience = a.int_value_or("--patience", 10, 1, 1 << 20);
  spec.val_windows = a.int_value_or("--val-windows", data ? 48 : 16, 1, 1 << 20);
  spec.seed = std::uint64_t(a.int_value_or("--seed", 1, 0, 1 << 30));
  spec.adam.lr = a.number_or("--lr", 1e-3, 0, 1, true);
  spec.adam.step_size = a.int_value_or("--lr-step-epochs", spec.stage == "mask" ? 5 : 10, 1, 1 << 20);
  spec.adam.weight_decay = 1e-5;
  spec.lr_schedule = a.value_or("--lr-schedule", "cosine");
  if (spec.lr_schedule != "cosine" && spec.lr_schedule != "step")
    throw UsageError("--lr-schedule '" + spec.lr_schedule + "': expected cosine or step");
  spec.warmup_steps = a.int_value_or("--warmup-steps", std::min<int>(100, int(spec.steps / 10)), 0, 1 << 30);
  spec.history_s = a.number_or("--history", 5, 0, 60);
  spec.windows_per_visit = a.int_value_or("--windows-per-visit", 8, 1, 1 << 10);
  if (a.value("--windows-per-visit") && !data) throw UsageError("--windows-per-visit: for --data only (recordings on disk)");
  spec.read_threads = a.int_value_or("--read-threads", 0, 1, 1024);
  if (a.value("--read-threads") && !data) throw UsageError("--read-threads: for --data only (recordings on disk)");
  spec.occlusion = a.flag("--occlusion");
  spec.warp = a.flag("--warp");
  spec.flip = a.flag("--flip");
  spec.frame_zoom = a.flag("--frame-zoom");
  spec.swap_loss = a.flag("--swap-loss");
  if (spec.swap_loss && spec.stage != "pose") throw UsageError("--swap-loss: for --stage pose only");
  if (spec.frame_zoom && (spec.warp || spec.stage != "pose")) throw UsageError("--frame-zoom: for --stage pose, without --warp");
  spec.empty_weight = float(a.number_or("--empty-weight", 1, 0, 1e3, true));
  if (spec.empty_weight != 1 && spec.stage != "mask") throw UsageError("--empty-weight: for --stage mask only");
  spec.dice_weight = float(a.number_or("--dice-weight", 0, 0, 100));
  if (spec.dice_weight != 0 && spec.stage != "mask") throw UsageError("--dice-weight: for --stage mask only");
  spec.mask_focus = a.int_value_or("--mask-focus", 0, 0, 1 << 10);
  if (spec.mask_focus != 0 && spec.stage != "mask") throw UsageError("--mask-focus: for --stage mask only");
  spec.mask_weights = a.value_or("--mask-weights", "");
  spec.mask_reuse = a.int_value_or("--mask-reuse", 0, 0, spec.cfg.n_masks);
  if (spec.mask_reuse && (spec.stage != "pose" || spec.mask_weights.empty()))
    throw UsageError("--mask-reuse: for --stage pose behind --mask-weights (stage 1's future masks, reused as yelan run's early exit does)");
  spec.init_weights = a.value_or("--init", "");
  spec.checkpoint_minutes = a.number_or("--checkpoint-minutes", 10, 0, 1e6, true);
  spec.max_minutes = a.number_or("--max-minutes", 0, 0, 1e7, true);  // absent: no limit
  spec.max_cpu_minutes = a.number_or("--max-cpu-minutes", 0, 0, 1e7, true);
  spec.resume = a.flag("--resume");
  spec.validate_start = a.flag("--validate-start");
  spec.freeze_bn = a.flag("--freeze-bn");
  if (spec.freeze_bn && spec.stage != "pose") throw UsageError("--freeze-bn: for --stage pose only");
  spec.progress_tty = &err == &std::cerr && ::isatty(STDERR_FILENO) && !a.flag("--quiet");
  const train::TrainResult r = train::train(spec, err);
  out << spec.out_dir << ": " << r.steps << " steps, last loss " << r.last_loss << ", best validation " << r.best_val
      << (r.early_stopped ? " (early stop)" : "") << (r.interrupted ? " (interrupted; --resume continues)" : "") << "\n";
  return r.interrupted ? kRuntimeError : kOk;
}

}  // namespace yelan::cli
