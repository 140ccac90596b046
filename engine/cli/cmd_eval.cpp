// `yelan eval`: MPJPE, PCK@150 and AUC of a weights file on simulated test scenes or on
// labelled recordings on disk.
#include <filesystem>
#include <fstream>

#include "camera/io/event_writer.h"
#include "camera/sim/presets.h"
#include "camera/sim/recording_windows.h"
#include "engine/cli/args.h"
#include "engine/cli/cli.h"
#include "engine/cli/handlers.h"
#include "engine/threads.h"
#include "engine/train/evaluate.h"

namespace yelan::cli {

std::vector<camera::sim::SimSpec> scenes_from(const std::string& text);  // cmd_train.cpp

int cmd_eval(const std::vector<std::string>& argv, std::ostream& out, std::ostream& err) {
  const Args a("eval", argv, {"--weights", "--sim", "--data", "--seed", "--scenes", "--json", "--seconds", "--threads", "--history"},
               {"--true-mask", "--no-floors"});
  a.expect_positionals(0, 0);
  const auto wpath = a.value("--weights"), simv = a.value("--sim"), data = a.value("--data");
  if (!wpath || (!simv && !data)) throw UsageError("eval needs --weights W and --sim test|PRESETS or --data DIR");
  if (simv && data) throw UsageError("give --sim or --data, not both");
  train::EvalSpec spec;
  spec.weights = *wpath;
  spec.seed = std::uint64_t(a.int_value_or("--seed", 1, 0, 1 << 30));
  spec.seconds_per_scene = std::stod(a.value_or("--seconds", "1"));
  spec.true_mask = a.flag("--true-mask");
  spec.floors = !a.flag("--no-floors");
  spec.history_s = std::stod(a.value_or("--history", "5"));
  if (!(spec.history_s >= 0 && spec.history_s <= 60)) throw UsageError("--history: expected 0-60 seconds");
  if (data) {
    try {
      spec.recordings = camera::sim::list_recordings(*data);
    } catch (const std::runtime_error& e) {
      throw UsageError(std::string("--data: ") + e.what());
    }
  } else if (*simv == "test") {
    for (const auto& n : train::draw_test_scenes(spec.seed, a.int_value_or("--scenes", 48, 1, 1 << 20)))
      spec.scenes.push_back(camera::sim::preset_spec(n));
  } else {
    spec.scenes = scenes_from(*simv);
  }
  if (const auto t = a.value("--threads")) {
    const auto n = parse_thread_count(*t);
    if (!n) throw UsageError("--threads '" + *t + "': expected 1..1024");
    set_threads(*n);
  }
  const train::EvalResult r = train::evaluate(spec, err);
  out << train::eval_table(r);
  if (const auto j = a.value("--json")) {
    const std::string tmp = camera::temp_path_for(*j);
    {
      std::ofstream f(tmp);
      f << train::eval_json(r);
      if (!f) throw std::runtime_error("cannot write " + tmp);
    }
    std::filesystem::rename(tmp, *j);
  }
  return kOk;
}

}  // namespace yelan::cli
