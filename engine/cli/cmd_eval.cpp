// `yelan eval`: MPJPE, PCK@150 and AUC of a weights file on simulated test scenes or on
// labelled recordings on disk.
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

#include <nlohmann/json.hpp>

#include "camera/io/event_writer.h"
#include "camera/sim/presets.h"
#include "camera/sim/recording_windows.h"
#include "camera/sim/rng.h"
#include "engine/cli/args.h"
#include "engine/cli/cli.h"
#include "engine/cli/handlers.h"
#include "engine/cli/output_path.h"
#include "engine/cli/vet_recordings.h"
#include "engine/run/stream_eval.h"
#include "engine/threads.h"
#include "engine/train/evaluate.h"

namespace yelan::cli {

std::vector<camera::sim::SimSpec> scenes_from(const std::string& text);  // cmd_train.cpp

namespace {

// {"low": {"dancer_ticks": N, "dancer_called_person": N, "empty_ticks": N, "empty_called_person": N}, ...}
std::string presence_json(const std::map<std::string, run::PresenceReport::Condition>& by_condition) {
  nlohmann::ordered_json j = nlohmann::ordered_json::object();
  for (const auto& [name, c] : by_condition)
    j[name] = {{"dancer_ticks", c.person_ticks}, {"dancer_called_person", c.person_called}, {"empty_ticks", c.empty_ticks},
               {"empty_called_person", c.empty_called}};
  return j.dump();
}

// The deployed masks' IoU, keyed as eval's frame by frame: "mask_iou" null where not measured.
std::string mask_iou_json(const run::StreamEvalResult& r) {
  nlohmann::ordered_json j = {{"mask_iou", r.mask_iou >= 0 ? nlohmann::ordered_json(r.mask_iou) : nlohmann::ordered_json(nullptr)},
                              {"mask_ticks", r.mask_ticks},
                              {"mask_iou_by_condition", r.mask_iou_by_condition},
                              {"mask_iou_sensor_px", r.mask_iou_px >= 0 ? nlohmann::ordered_json(r.mask_iou_px) : nlohmann::ordered_json(nullptr)},
                              {"mask_iou_sensor_px_by_condition", r.mask_iou_px_by_condition}};
  nlohmann::ordered_json by_age = nlohmann::ordered_json::object();
  for (const auto& [age, a] : r.mask_iou_by_age) by_age[std::to_string(age)] = {{"iou", a.iou}, {"ticks", a.ticks}};
  j["mask_iou_by_age"] = by_age;
  const std::string s = j.dump();
  return s.substr(1, s.size() - 2);  // the members, spliced into the object below
}

// The deployed path: `yelan run`'s pipeline on the test scenes (events in time order, TORE of
// everything so far, stage 1 with the model's early exit, its own depth from the body-height
// prior), each pose scored against the label at its time; root-aligned is the figure to
// compare with eval's root-aligned one.
int eval_run(const train::EvalSpec& spec, const Args& a, std::ostream& out, std::ostream& err) {
  run::RunOptions o;
  if (a.flag("--no-early-exit") && a.value("--beta")) throw UsageError("give --beta or --no-early-exit, not both");
  o.beta = a.flag("--no-early-exit") ? 2.0 : a.number_or("--beta", o.beta, 0, 1);  // > 1: stage 1 on every tick
  if (a.value("--depth-tau")) o.depth_tau_s = a.number_or("--depth-tau", 0, 0, 60);
  if (a.value("--pose-tau")) o.pose_tau_s = a.number_or("--pose-tau", 0, 0, 10);
  if (a.value("--mask-max-age")) o.mask_max_age = a.int_value_or("--mask-max-age", 0, 0, 1000);
  if (a.value("--mask-crop-margin")) o.mask_crop_margin = a.int_value_or("--mask-crop-margin", 0, 0, 4096);
  if (a.value("--bf16")) o.bf16 = a.on_off("--bf16");
  if (a.value("--pose-bf16")) o.pose_bf16 = a.on_off("--pose-bf16");
  o.mask_grow = spec.mask_grow;
  const bool keep = a.value("--poses").has_value();
  run::StreamEvalResult r;
  std::string what;  // "N recordings" or "N scenes"
  std::size_t count = 0;
  if (!spec.recordings.empty()) {
    // The first --skip s of a recording (the TORE still filling) are not scored, as calibrate does.
    const double skip = a.number_or("--skip", 0.5, 0, 3600);
    vet_recordings_up_front(spec.recordings, err);
    r = run::evaluate_recordings(spec.weights, spec.recordings, spec.seconds_per_scene, skip, o, err, keep);
    count = spec.recordings.size();
    what = std::to_string(count) + " recordings";
  } else {
    std::vector<camera::sim::SimSpec> scenes = spec.scenes;
    for (std::size_t i = 0; i < scenes.size(); ++i) train::place_in_clip(scenes[i], spec.seed, i, spec.framed);
    const auto sims = run::simulate_scenes(scenes, spec.seed, spec.seconds_per_scene, std::max(0.1, spec.history_s), err);
    r = run::evaluate_stream(spec.weights, sims, o, keep);
    count = scenes.size();
    what = std::to_string(count) + " scenes";
  }
  std::ostringstream t;
  t << std::fixed << std::setprecision(1) << "deployed path (yelan run, its own depth), " << what << ", " << r.poses_scored;
  if (r.poses_scored == 0)
    t << " poses scored (no pose of a dancer in the picture said person): MPJPE n/a";
  else
    t << " poses: MPJPE " << r.deployed.mpjpe_mm << " mm, root-aligned " << r.deployed.mpjpe_root_mm << " mm, PCK@150 "
      << std::setprecision(3) << r.deployed.pck150 << std::setprecision(1) << "; with the true head depth: MPJPE "
      << r.paper.mpjpe_mm << " mm, root-aligned " << r.paper.mpjpe_root_mm << " mm";
  t << "; stage 1 on " << std::setprecision(0) << 100 * r.mask_run_fraction << "% of ticks ("
    << r.stage1_precision << (r.stage2_bf16 ? ", stage 2 bf16 on AMX" : "") << ", age cap " << r.mask_max_age << ")";
  if (r.mirror_runs) t << " (mirrored too on " << std::setprecision(1) << 100 * r.mirror_run_fraction << "%)";
  if (r.mask_crop_runs)
    t << " (on " << std::setprecision(1) << 100 * r.mask_crop_share << "% of the frame on the " << r.mask_crop_runs << " runs on a crop)";
  t << "\n";
  t << std::setprecision(1) << "head depth as deployed: mean |error| " << r.depth_abs_error_mm << " mm, median estimate / truth "
    << std::setprecision(3) << r.depth_ratio_median << "\n";
  const std::uint64_t shown = r.person_found + r.person_missed;
  t << "presence: a person reported on " << std::setprecision(1) << (shown ? 100.0 * double(r.person_found) / double(shown) : 0.0)
    << "% of the " << shown << " poses whose frame shows the dancer (" << r.person_missed
    << " said no person: not scored)";
  if (r.dancer_hidden) {
    const std::uint64_t visible = r.dancer_shown(), visible_found = r.dancer_shown_called();
    t << "; on " << (visible ? 100.0 * double(visible_found) / double(visible) : 0.0) << "% of the " << visible
      << " where any pixel of the dancer shows (" << r.dancer_hidden << " with the dancer wholly hidden, "
      << r.dancer_hidden_called << " of them said person)";
  }
  if (r.empty_poses)
    t << "; on " << 100.0 * double(r.empty_called_person) / double(r.empty_poses) << "% of the " << r.empty_poses
      << " poses of scenes with nobody";
  t << "\n";
  if (r.mask_iou >= 0) {
    t << std::setprecision(3) << "mask IoU as deployed (the mask stage 2 read: this tick's, or a future one reused): "
      << r.mask_iou << " over " << r.mask_ticks << " ticks of dancer " << (spec.recordings.empty() ? "scenes" : "recordings")
      << "; by condition:";
    for (const auto& [c, iou] : r.mask_iou_by_condition) t << " " << c << " " << iou;
    t << "\nthe same at the sensor's pixels (each with its cell's verdict): " << r.mask_iou_px << "; by condition:";
    for (const auto& [c, iou] : r.mask_iou_px_by_condition) t << " " << c << " " << iou;
    t << "\nthe same by the age of the mask in use (0: this tick's; k: a future mask reused k ticks after stage 1 ran):";
    for (const auto& [age, a] : r.mask_iou_by_age) t << " " << age << ": " << a.iou << " (" << a.ticks << " ticks)";
    t << "\n";
  }
  if (!r.presence_by_condition.empty()) {
    t << "presence by the conditions in the " << (spec.recordings.empty() ? "scenes'" : "recordings'") << " names (every pose in the span):\n";
    run::print_presence_by_condition(r.presence_by_condition, t);
  }
  out << t.str();
  if (const auto j = a.value("--json"))
    camera::write_file_atomically(*j, "{\"deployed\": " + train::pose_scores_json(r.deployed) + ", \"paper\": " +
                             train::pose_scores_json(r.paper) + ", \"scenes\": " +
                             std::to_string(count) +
                             ", \"mask_run_fraction\": " + std::to_string(r.mask_run_fraction) +
                             ", \"stage1_bf16\": " + std::string(r.stage1_bf16 ? "true" : "false") +
                             ", \"stage1_precision\": \"" + r.stage1_precision + "\"" +
                             ", \"stage2_bf16\": " + std::string(r.stage2_bf16 ? "true" : "false") +
                             ", \"mask_max_age\": " + std::to_string(r.mask_max_age) +
                             ", \"mirror_run_fraction\": " + std::to_string(r.mirror_run_fraction) +
                             ", \"mask_crop_runs\": " + std::to_string(r.mask_crop_runs) +
                             ", \"mask_crop_share\": " + std::to_string(r.mask_crop_share) +
                             ", \"stage1_ms_per_tick\": " + std::to_string(r.stage1_ms) +
                             ", \"ms_per_tick\": " + std::to_string(r.ms_per_tick) +
                             ", \"person_found\": " + std::to_string(r.person_found) +
                             ", \"person_missed\": " + std::to_string(r.person_missed) +
                             ", \"dancer_hidden\": " + std::to_string(r.dancer_hidden) +
                             ", \"dancer_hidden_called_person\": " + std::to_string(r.dancer_hidden_called) +
                             ", \"empty_poses\": " + std::to_string(r.empty_poses) +
                             ", \"empty_called_person\": " + std::to_string(r.empty_called_person) +
                             ", \"head_depth_abs_error_mm\": " + std::to_string(r.depth_abs_error_mm) +
                             ", \"head_depth_ratio_median\": " + std::to_string(r.depth_ratio_median) +
                             ", \"presence_by_condition\": " + presence_json(r.presence_by_condition) +
                             ", " + mask_iou_json(r) + "}\n");
  if (const auto p = a.value("--poses")) camera::write_file_atomically(*p, run::scored_poses_csv(r.poses));
  return kOk;
}

}  // namespace

int cmd_eval(const std::vector<std::string>& argv, std::ostream& out, std::ostream& err) {
  const Args a("eval", argv, {"--weights", "--sim", "--data", "--seed", "--scenes", "--json", "--seconds", "--threads", "--history", "--beta", "--skip",
                "--low-light-dn", "--poses", "--depth-tau", "--pose-tau", "--mask-pictures", "--mask-grow", "--mask-max-age",
                 "--mask-crop-margin", "--bf16", "--pose-bf16"},
               {"--true-mask", "--no-floors", "--run", "--unframed", "--frame-zoom", "--no-early-exit"});
  a.expect_positionals(0, 0);
  const auto wpath = a.value("--weights"), simv = a.value("--sim"), data = a.value("--data");
  if (!wpath || (!simv && !data)) throw UsageError("eval needs --weights W and --sim test|PRESETS or --data DIR");
  if (simv && data) throw UsageError("give --sim or --data, not both");
  // Refused before the recordings are listed: a usage error names the flag whatever DIR holds.
  if (data && a.value("--low-light-dn"))
    throw UsageError("--low-light-dn is for --sim scenes (a recording's light is in its events)");
  if (const auto j = a.value("--json")) check_output("--json", *j, {*wpath});
  if (a.value("--mask-max-age") && !a.flag("--run")) throw UsageError("--mask-max-age is for eval --run (the deployed path)");
  if (a.value("--mask-crop-margin") && !a.flag("--run")) throw UsageError("--mask-crop-margin is for eval --run (the deployed path)");
  if (a.value("--bf16") && !a.flag("--run")) throw UsageError("--bf16 is for eval --run (the deployed path)");
  if (a.value("--pose-bf16") && !a.flag("--run")) throw UsageError("--pose-bf16 is for eval --run (the deployed path)");
  if (a.flag("--no-early-exit") && !a.flag("--run"))
    throw UsageError("--no-early-exit is for eval --run (frame by frame, stage 1 runs on every frame)");
  if (const auto p = a.value("--poses")) check_output("--poses", *p, {*wpath});
  if (const auto t = a.value("--threads")) {
    const auto n = parse_thread_count(*t);
    if (!n) throw UsageError("--threads '" + *t + "': expected 1..1024");
    set_threads(*n);
  }
  train::EvalSpec spec;
  spec.weights = *wpath;
  if (const auto pics = a.value("--mask-pictures")) {
    if (a.flag("--run") || a.flag("--true-mask"))
      throw UsageError("--mask-pictures shows stage 1's masks as eval scores them: not with --run or --true-mask");
    std::error_code ec;
    std::filesystem::create_directories(*pics, ec);
    if (ec) throw UsageError("--mask-pictures " + *pics + ": cannot make the folder (" + ec.message() + ")");
    if (!std::filesystem::is_directory(*pics)) throw UsageError("--mask-pictures " + *pics + ": exists and is not a folder");
    spec.mask_pictures = *pics;
  }
  spec.seed = std::uint64_t(a.int_value_or("--seed", 1, 0, 1 << 30));
  spec.seconds_per_scene = a.number_or("--seconds", 1, 0, 3600, true);
  spec.true_mask = a.flag("--true-mask");
  spec.frame_zoom = a.flag("--frame-zoom");
  spec.floors = !a.flag("--no-floors");
  spec.framed = !a.flag("--unframed");
  spec.history_s = a.number_or("--history", 5, 0, 60);
  if (a.value("--mask-grow")) spec.mask_grow = a.int_value_or("--mask-grow", 0, 0, 64);
  spec.keep_poses = a.value("--poses").has_value();
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
    // --scenes M: M of them drawn with the seed (all when the list is shorter).
    const int m = a.int_value_or("--scenes", int(spec.scenes.size()), 1, 1 << 20);
    std::vector<camera::sim::SimSpec> picked;
    for (std::size_t i = 0; i < spec.scenes.size() && int(picked.size()) < m; ++i) {
      const std::size_t j = i + camera::sim::hash64(spec.seed, 0x5ce7e5, i) % (spec.scenes.size() - i);
      std::swap(spec.scenes[i], spec.scenes[j]);
      picked.push_back(spec.scenes[i]);
    }
    spec.scenes = picked;
  }
  if (a.value("--low-light-dn")) {
    const double dn = a.number_or("--low-light-dn", 20, 1e-3, 1e5);
    for (auto& sc : spec.scenes) camera::sim::set_low_light_dn(sc.scene, dn);
  }
  if (a.flag("--run")) return eval_run(spec, a, out, err);
  if (data) vet_recordings_up_front(spec.recordings, err);
  const train::EvalResult r = train::evaluate(spec, err);
  out << train::eval_table(r);
  if (!spec.mask_pictures.empty() && r.mask_pictures == 0)
    err << "yelan: warning: --mask-pictures: no picture written (this model's stage 2 reads no mask, so eval runs no stage 1:\n"
           "  combine its mask net with a config whose pose.masked_input is true, or use yelan run --viz)\n";
  else if (!spec.mask_pictures.empty())
    out << "wrote " << r.mask_pictures << " pictures of stage 1 against the truth to " << spec.mask_pictures
        << " (green: both, red: stage 1 alone, blue: the truth alone; the last frame of each recording's middle window)\n";
  if (const auto j = a.value("--json")) camera::write_file_atomically(*j, train::eval_json(r));
  if (const auto p = a.value("--poses")) camera::write_file_atomically(*p, train::frame_poses_csv(r.poses));
  return kOk;
}

}  // namespace yelan::cli
