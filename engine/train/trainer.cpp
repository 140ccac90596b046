#include "engine/train/trainer.h"

#include <signal.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <ctime>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <optional>
#include <set>
#include <span>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "camera/io/event_writer.h"
#include "camera/sim/rng.h"
#include "camera/sim/recording_windows.h"
#include "camera/sim/window_stream.h"
#include "engine/input.h"
#include "engine/losses.h"
#include "engine/mask_net.h"
#include "engine/pose_net.h"
#include "engine/threads.h"
#include "engine/train/batch.h"
#include "weights_tools/network_io.h"
#include "weights_tools/weights_file.h"

namespace yelan::train {

namespace sim = camera::sim;
namespace fs = std::filesystem;

namespace {

// SIGINT / SIGTERM during training: finish the step, write a checkpoint, stop.
std::atomic<int> g_stop_signal{0};
void on_stop_signal(int sig) { g_stop_signal.store(sig); }

// Installs the handlers for the run and puts the previous ones back after it.
class StopOnSignal {
 public:
  StopOnSignal() {
    g_stop_signal.store(0);
    struct sigaction sa {};
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    ::sigaction(SIGINT, &sa, &old_int_);
    ::sigaction(SIGTERM, &sa, &old_term_);
  }
  ~StopOnSignal() {
    ::sigaction(SIGINT, &old_int_, nullptr);
    ::sigaction(SIGTERM, &old_term_, nullptr);
  }
  int signal() const { return g_stop_signal.load(); }

 private:
  struct sigaction old_int_ {}, old_term_ {};
};

constexpr char kStateMagic[8] = {'Y', 'E', 'L', 'A', 'N', 'T', 'R', 'N'};
constexpr std::uint32_t kStateVersion = 3;
constexpr const char* kLogHeader =
    "step,epoch,loss,val_loss,lr,grad_norm,samples_per_s,wall_s,val_mpjpe_mm,cpu_s,val_mask_iou";
constexpr int kLogCommas = 10;

// One row of log.csv, in kLogHeader's order; -1 where a value does not apply to the row.
struct LogRow {
  std::int64_t step;
  int epoch;
  double loss, val_loss, lr, grad_norm, samples_per_s, wall_s, val_mpjpe_mm, cpu_s, val_mask_iou;
};

void write_log_row(std::ostream& log, const LogRow& r) {
  log << r.step << "," << r.epoch << "," << std::setprecision(9) << r.loss << "," << r.val_loss << "," << r.lr << ","
      << r.grad_norm << "," << std::setprecision(4) << r.samples_per_s << "," << r.wall_s << "," << r.val_mpjpe_mm << ","
      << std::setprecision(6) << r.cpu_s << "," << std::setprecision(4) << r.val_mask_iou << "\n";
  log.flush();
}

// The learning rate at a step under the spec's schedule (cosine: a function of the step
// alone, so --resume needs nothing more).
double scheduled_lr(const TrainSpec& s, std::int64_t step) {
  const double lr0 = s.adam.lr;
  if (s.warmup_steps > 0 && step < s.warmup_steps) return lr0 * (0.1 + 0.9 * double(step) / s.warmup_steps);
  const double span = double(std::max<std::int64_t>(1, s.steps - s.warmup_steps));
  const double u = std::clamp(double(step - s.warmup_steps) / span, 0.0, 1.0);
  const double lo = lr0 * s.lr_min_ratio;
  return lo + (lr0 - lo) * 0.5 * (1 + std::cos(3.141592653589793 * u));
}

struct State {
  std::uint64_t weights_hash = 0;  // of checkpoint.h5: the pair must belong together
  std::int64_t step = 0;
  std::int64_t adam_t = 0;
  std::int32_t adam_epochs = 0;
  double lr = 0, best_val = 1e30;
  std::int32_t bad_epochs = 0;
  double cpu_s = 0;  // CPU seconds of every run before this checkpoint (version 3 on)
  std::vector<float> moments;
};

template <class T>
void put(std::ostream& o, const T& v) {
  o.write(reinterpret_cast<const char*>(&v), sizeof v);
}
template <class T>
void get(std::istream& in, T& v, const std::string& path) {
  if (!in.read(reinterpret_cast<char*>(&v), sizeof v)) throw std::runtime_error(path + ": truncated trainer state");
}

void save_state(const std::string& path, const State& s) {
  camera::TempFile tmp(path);
  {
    std::ofstream o(tmp.path(), std::ios::binary);
    o.write(kStateMagic, 8);
    put(o, kStateVersion);
    put(o, s.weights_hash);
    put(o, s.step), put(o, s.adam_t), put(o, s.adam_epochs), put(o, s.lr), put(o, s.best_val), put(o, s.bad_epochs);
    put(o, s.cpu_s);
    const std::uint64_t n = s.moments.size();
    put(o, n);
    o.write(reinterpret_cast<const char*>(s.moments.data()), std::streamsize(n * sizeof(float)));
    o.flush();
    if (!o) throw std::runtime_error("cannot write " + tmp.path());
  }
  tmp.commit();
}

State load_state(const std::string& path, std::size_t expect_moments) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot read (nothing to resume?)");
  char magic[8];
  if (!in.read(magic, 8) || std::memcmp(magic, kStateMagic, 8) != 0)
    throw std::runtime_error(path + ": offset 0: not a yelan trainer state");
  std::uint32_t version;
  get(in, version, path);
  if (version != kStateVersion && version != 2) throw std::runtime_error(path + ": trainer state version " + std::to_string(version));
  State s;
  get(in, s.weights_hash, path);
  get(in, s.step, path), get(in, s.adam_t, path), get(in, s.adam_epochs, path), get(in, s.lr, path);
  get(in, s.best_val, path), get(in, s.bad_epochs, path);
  if (version >= 3) get(in, s.cpu_s, path);
  std::uint64_t n;
  get(in, n, path);
  if (n != expect_moments)
    throw std::runtime_error(path + ": " + std::to_string(n) + " optimizer moments, this model needs " +
                             std::to_string(expect_moments));
  s.moments.resize(n);
  if (!in.read(reinterpret_cast<char*>(s.moments.data()), std::streamsize(n * sizeof(float))))
    throw std::runtime_error(path + ": truncated trainer state");
  return s;
}

// FNV-1a of a file's bytes.
std::uint64_t file_hash(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::uint64_t h = 1469598103934665603ull;
  char buf[1 << 16];
  while (in.read(buf, sizeof buf) || in.gcount() > 0) {
    for (std::streamsize i = 0; i < in.gcount(); ++i) h = (h ^ static_cast<unsigned char>(buf[i])) * 1099511628211ull;
    if (!in) break;
  }
  return h;
}

// The log up to (and including) `step`: a resumed run rewrites what came after the checkpoint.
void truncate_log(const std::string& path, std::int64_t step) {
  static const std::string header = kLogHeader;
  std::ifstream in(path);
  std::string line, kept = header + "\n";
  while (std::getline(in, line)) {
    // Only whole rows at or before the checkpoint (a crash can cut the last one short).
    if (line.rfind("step,", 0) == 0) continue;  // a header, this one or an older one
    const auto commas = std::count(line.begin(), line.end(), ',');
    if (commas == kLogCommas - 1) line += ",-1";  // a row from before val_mask_iou
    else if (commas != kLogCommas) continue;
    std::int64_t at = 0;
    try {
      at = std::stoll(line.substr(0, line.find(',')));
    } catch (const std::exception&) {
      continue;
    }
    if (at > step) break;
    kept += line + "\n";
  }
  in.close();
  camera::TempFile tmp(path);
  std::ofstream(tmp.path()) << kept;
  tmp.commit();
}

// A run.json key as the command line spells its flag (frame_zoom: frame-zoom).
std::string flag_name(std::string key) {
  std::replace(key.begin(), key.end(), '_', '-');
  return key;
}

std::string eta_text(double s) {
  std::ostringstream o;
  if (s >= 3600) o << int(s / 3600) << "h" << std::setw(2) << std::setfill('0') << int(s / 60) % 60 << "m";
  else if (s >= 60) o << int(s / 60) << "m" << std::setw(2) << std::setfill('0') << int(s) % 60 << "s";
  else o << int(s) << "s";
  return o.str();
}

// Windows from the simulator or from recordings on disk, behind one interface.
class WindowSource {
 public:
  WindowSource(const std::vector<sim::SimSpec>& scenes, const std::vector<std::string>& recordings, std::uint64_t seed,
               const sim::WindowStreamOptions& o) {
    if (!recordings.empty()) rec_ = std::make_unique<sim::RecordingWindowStream>(recordings, seed, o);
    else sim_ = std::make_unique<sim::SimWindowStream>(scenes, seed, o);
  }
  void next(sim::SimWindow& w) { rec_ ? rec_->next(w) : sim_->next(w); }
  void next_batch(std::span<sim::SimWindow> ws, int threads) {
    if (rec_) return rec_->next_batch(ws, threads);
    for (sim::SimWindow& w : ws) sim_->next(w);
  }
  void seek(std::uint64_t k) { rec_ ? rec_->seek_window(k) : sim_->seek_scene(k); }

 private:
  std::unique_ptr<sim::SimWindowStream> sim_;
  std::unique_ptr<sim::RecordingWindowStream> rec_;
};

}  // namespace

TrainResult train(const TrainSpec& spec, std::ostream& err) {
  const ModelConfig& cfg = spec.cfg;
  const bool pose_stage = spec.stage == "pose";
  if (!pose_stage && spec.stage != "mask") throw std::invalid_argument("stage must be mask or pose, got '" + spec.stage + "'");
  if (spec.scenes.empty() && spec.data.empty()) throw std::invalid_argument("no training scenes or recordings");
  if (!spec.data.empty() && spec.val_data.empty()) throw std::invalid_argument("recordings for training but none for validation");
  if (spec.out_dir.empty()) throw std::invalid_argument("no output folder");
  if (spec.batch < 1 || spec.steps < 1 || spec.steps_per_epoch < 1)
    throw std::invalid_argument("batch, steps and steps per epoch must be >= 1");
  if (spec.lr_schedule != "cosine" && spec.lr_schedule != "step")
    throw std::invalid_argument("LR schedule must be cosine or step, got '" + spec.lr_schedule + "'");
  const bool cosine = spec.lr_schedule == "cosine";
  if (spec.empty_weight != 1 && pose_stage) throw std::invalid_argument("the empty-scene weight is for the mask stage");
  if (spec.freeze_bn && !pose_stage) throw std::invalid_argument("frozen BatchNorm statistics are for the pose stage");
  if (!(spec.empty_weight > 0)) throw std::invalid_argument("the empty-scene weight must be > 0");
  if (spec.dice_weight != 0 && pose_stage) throw std::invalid_argument("the Dice weight is for the mask stage");
  if (!(spec.dice_weight >= 0)) throw std::invalid_argument("the Dice weight must be >= 0");
  if (spec.mask_focus != 0 && pose_stage) throw std::invalid_argument("the mask focus is for the mask stage");
  if (spec.mask_focus < 0 || spec.mask_focus >= cfg.n_masks)
    throw std::invalid_argument("the mask focus " + std::to_string(spec.mask_focus) + " is outside 0.." +
                                std::to_string(cfg.n_masks - 1) + " (the config's future masks)");
  if (spec.windows_per_visit < 1) throw std::invalid_argument("windows per visit must be >= 1");
  if (spec.mask_reuse < 0 || spec.mask_reuse > spec.cfg.n_masks || (spec.mask_reuse > 0 && (!pose_stage || spec.mask_weights.empty())))
    throw std::invalid_argument("mask reuse: the pose stage behind a frozen mask net (mask weights) only, every 1.." +
                                std::to_string(spec.cfg.n_masks) + " frames (the config's future masks)");
  if (spec.mask_frames < 0 || (pose_stage && spec.mask_frames > 0))
    throw std::invalid_argument("frames per mask window: the mask stage only, and >= 1");
  // The training windows' shape; validation, weights and the saved config keep cfg's.
  ModelConfig tcfg = cfg;
  if (spec.mask_frames > 0) tcfg.window = spec.mask_frames;
  if (spec.mask_frames > 0 && spec.mask_frames != cfg.window)
    err << "training windows of " << spec.mask_frames << " frame" << (spec.mask_frames > 1 ? "s" : "")
        << " (--mask-frames); validation windows of the config's " << cfg.window << "\n";
  fs::create_directories(spec.out_dir);
  const std::string ckpt = (fs::path(spec.out_dir) / "checkpoint.h5").string();
  const std::string state_path = (fs::path(spec.out_dir) / "checkpoint.state").string();
  const std::string log_path = (fs::path(spec.out_dir) / "log.csv").string();
  const std::string run_json = (fs::path(spec.out_dir) / "run.json").string();
  // The run being resumed, as its run.json says (null: none, or not resuming).
  nlohmann::json resumed;
  if (spec.resume && fs::exists(run_json)) {
    std::ifstream in(run_json);
    resumed = nlohmann::json::parse(in, nullptr, false);
    if (resumed.is_discarded()) resumed = nullptr;
  }
  // Another loss is another run (run.json without the key: the option was off).
  const int focus = resumed.contains("mask_focus") && resumed["mask_focus"].is_number_integer() ? resumed["mask_focus"].get<int>() : 0;
  if (!resumed.is_null() && focus != spec.mask_focus)
    throw std::invalid_argument(run_json + ": the run was trained with --mask-focus " + std::to_string(focus) + ", not " +
                                std::to_string(spec.mask_focus) + " (resume with the run's)");
  // A resumed run reads the recordings it started with, even if the dataset grew since.
  std::vector<std::string> train_files = spec.data, val_files = spec.val_data;
  if (!spec.data.empty() && resumed.contains("train_files") && resumed["train_files"].is_array() && resumed.contains("val_files")) {
    // Another number of windows per visit draws other windows: not the run being resumed.
    const int wpv = resumed.contains("windows_per_visit") && resumed["windows_per_visit"].is_number_integer() ? resumed["windows_per_visit"].get<int>() : 8;
    if (wpv != spec.windows_per_visit)
      throw std::invalid_argument(run_json + ": the run read " + std::to_string(wpv) + " windows per visit, not " +
                                  std::to_string(spec.windows_per_visit) + " (resume with --windows-per-visit " +
                                  std::to_string(wpv) + ")");
    // Nor does a run with other augmentations (run.json without a key: the option was off).
    for (const auto& [key, on] : {std::pair<const char*, bool>{"occlusion", spec.occlusion}, {"warp", spec.warp}, {"flip", spec.flip},
                                {"frame_zoom", spec.frame_zoom}, {"swap_loss", spec.swap_loss}, {"freeze_bn", spec.freeze_bn}}) {
      const bool was = resumed.contains(key) && resumed[key].is_boolean() && resumed[key].get<bool>();
      if (was != on)
        throw std::invalid_argument(run_json + ": the run was trained " + (was ? "with" : "without") + " --" + flag_name(key) +
                                    " (resume " + (was ? "with" : "without") + " it)");
    }
    const int reuse = resumed.contains("mask_reuse") && resumed["mask_reuse"].is_number_integer() ? resumed["mask_reuse"].get<int>() : 0;
    if (reuse != spec.mask_reuse)
      throw std::invalid_argument(run_json + ": the run was trained with --mask-reuse " + std::to_string(reuse) + ", not " +
                                  std::to_string(spec.mask_reuse) + " (resume with the run's)");
    train_files = resumed["train_files"].get<std::vector<std::string>>();
    val_files = resumed["val_files"].get<std::vector<std::string>>();
    if (train_files.size() != spec.data.size() || val_files.size() != spec.val_data.size())
      err << "resuming with the run's own " << train_files.size() << " training and " << val_files.size()
          << " validation recordings (the folder now holds " << spec.data.size() << " and " << spec.val_data.size() << ")\n";
  }
  {
    // What the run is, for the curves and for anyone repeating it.
    const nlohmann::ordered_json j = {{"stage", spec.stage},           {"config", cfg.name},
                                      {"window", tcfg.window},         {"batch", spec.batch},
                                      {"steps", spec.steps},           {"steps_per_epoch", spec.steps_per_epoch},
                                      {"lr", spec.adam.lr},            {"lr_schedule", spec.lr_schedule},
                                      {"warmup_steps", spec.warmup_steps}, {"history_s", spec.history_s},
                                      {"windows_per_visit", spec.windows_per_visit},
                                      {"occlusion", spec.occlusion},   {"warp", spec.warp},
                                      {"flip", spec.flip},             {"frame_zoom", spec.frame_zoom},
                                      {"swap_loss", spec.swap_loss},   {"freeze_bn", spec.freeze_bn},
                                      {"mask_reuse", spec.mask_reuse},
                                      {"empty_weight", spec.empty_weight}, {"dice_weight", spec.dice_weight},
                                      {"mask_focus", spec.mask_focus},
                                      {"seed", spec.seed},
                                      {"mask_weights", spec.mask_weights}, {"init_weights", spec.init_weights},
                                      {"train_recordings", train_files.size()}, {"val_recordings", val_files.size()},
                                      {"val_windows", spec.val_windows}, {"config_json", cfg.json},
                                      {"train_files", train_files}, {"val_files", val_files}};
    camera::TempFile tmp(run_json);
    std::ofstream(tmp.path()) << j.dump(1) << "\n";
    tmp.commit();
  }

  MaskNet mask(cfg);
  PoseNet pose(cfg);
  layers::ParamList mp, pp;
  mask.params(mp);
  pose.params(pp);
  mask.init(spec.seed * 2 + 1);
  pose.init(spec.seed * 2 + 2);
  bool mask_loaded = false;
  if (!spec.init_weights.empty()) {
    // A checkpoint holds only the group it trained: a group is taken wherever the file has
    // one, and required for the stage trained (a pose stage reads a mask net only from
    // --mask-weights; without it, the true masks).
    const weights::Weights w = weights::load_weights(spec.init_weights);
    auto has = [&](const char* g) {
      const auto it = w.groups.find(g);
      return it != w.groups.end() && !it->second.empty();
    };
    if (!pose_stage || has("mask")) {
      weights::load_group(w, "mask", mp, spec.init_weights);
      mask_loaded = true;
    }
    // A net with depth maps may start from one without: its depth hourglasses keep their init.
    if (pose_stage || has("pose"))
      if (const std::size_t fresh = weights::load_group(w, "pose", pp, spec.init_weights, cfg.depth_map ? "depth_hm_cnns." : "")) {
        err << "note: " << spec.init_weights << " has no depth maps (pose.depth_map): " << fresh
            << " tensors of the depth hourglasses start from their init\n";
      }
  }
  if (pose_stage && cfg.masked_input && spec.mask_weights.empty() && !mask_loaded)
    err << "note: the pose net learns from the simulator's true masks; the mask group of the files written here is "
           "untrained (combine with a trained mask net: yelan weights combine; evaluate alone with --true-mask)\n";
  if (pose_stage && !spec.mask_weights.empty()) weights::load_group(weights::load_weights(spec.mask_weights), "mask", mp, spec.mask_weights);
  mask.weights_changed();
  pose.weights_changed();

  layers::ParamList& trained = pose_stage ? pp : mp;
  Adam adam(trained, spec.adam);
  State st;
  st.lr = spec.adam.lr;
  if (spec.resume) {
    const weights::Weights w = weights::load_weights(ckpt);
    // A checkpoint holds the trained group (older ones both).
    for (const auto& [g, params] : {std::pair<const char*, layers::ParamList*>{"mask", &mp}, {"pose", &pp}}) {
      const auto it = w.groups.find(g);
      if (it != w.groups.end() && !it->second.empty()) weights::load_group(w, g, *params, ckpt);
    }
    mask.weights_changed();
    pose.weights_changed();
    st = load_state(state_path, adam.moments().size());
    if (st.weights_hash != file_hash(ckpt))
      throw std::runtime_error(state_path + " does not belong to " + ckpt +
                               " (a run stopped between writing the two): cannot resume exactly");
    adam.set_state(st.moments, st.adam_t, st.adam_epochs, st.lr);
    // A run that validates its start and stopped before its first step writes that row again.
    truncate_log(log_path, spec.validate_start && st.step == 0 ? -1 : st.step);
    err << "resuming " << spec.out_dir << " at step " << st.step << "\n";
  } else {
    std::ofstream(log_path) << kLogHeader << "\n";
  }

  // One window per simulated scene: scene k feeds window k, whatever happened before.
  sim::WindowStreamOptions so;
  so.frame_hz = spec.frame_hz;
  so.warmup_s = 0.1;
  // Windows of `frames` read out, plus the mask net's future masks (targets alone).
  // With --mask-reuse, the frames before them that a stage-1 run may have read.
  const int lead = spec.mask_reuse > 0 ? spec.mask_reuse - 1 : 0;
  const int swap_group = spec.swap_loss ? cfg.window : 0;  // a window's frames are consecutive in a batch
  auto set_window = [&](sim::WindowStreamOptions& o, int frames) {
    o.window = lead + frames + (pose_stage ? 0 : cfg.n_masks - 1);
    o.tore_frames = lead + frames;
    o.scene_s = o.warmup_s + o.window / o.frame_hz + 1e-6;
  };
  set_window(so, tcfg.window);
  so.history_s = spec.history_s;
  if (spec.history_s * 1e6 >= double(so.tore.tau_us)) {
    // A batch's windows from `batch` recordings at once, several windows per visit read in
    // one pass: equal, value for value, to seeking each window (events past tau read 0).
    so.cursors = spec.batch;
    so.windows_per_visit = spec.windows_per_visit;
  }
  so.shuffle = true;
  so.counts = cfg.representation == "counts";
  WindowSource stream(spec.scenes, train_files, spec.seed, so);
  stream.seek(std::uint64_t(st.step) * std::uint64_t(spec.batch));
  std::vector<sim::SimSpec> val_scenes = spec.val_scenes.empty() ? spec.scenes : spec.val_scenes;
  const bool frozen_mask = pose_stage && !spec.mask_weights.empty();
  BatchBuilder builder(tcfg, spec.batch, pose_stage ? (frozen_mask ? MaskSource::net : MaskSource::truth) : MaskSource::none, lead);
  // The reuse of window b of step s (validation window i: kValReuse + i), its own stream.
  constexpr std::uint64_t kReuseStream = 0x5e05u, kValReuse = 0x5e05'0000'0000ull;
  // None without --mask-reuse: the windows are masked fresh.
  auto reuse_of = [&](std::uint64_t stream) -> std::optional<MaskReuse> {
    if (spec.mask_reuse <= 0) return std::nullopt;
    sim::Rng r(spec.seed, stream);
    return draw_mask_reuse(r, spec.mask_reuse);
  };

  std::ofstream log(log_path, std::ios::app);
  const std::clock_t cpu_start = std::clock();
  const double cpu_base = st.cpu_s;
  auto last_ckpt = std::chrono::steady_clock::now();
  const auto start = last_ckpt;
  // Weights first, then the state with the weights' checksum: a stop between the two is
  // detected on --resume instead of mixing two steps.
  auto checkpoint = [&] {
    // The trained group only (the other is the frozen mask net or the seeded initialisation,
    // both rebuilt on --resume): a pose checkpoint is about 1 MB, not the mask net's 8.
    weights::Weights w = weights::weights_of(cfg, mp, pp);
    w.groups.erase(pose_stage ? "mask" : "pose");
    weights::save_weights(ckpt, w);
    st.weights_hash = file_hash(ckpt);
    st.adam_t = adam.steps();
    st.adam_epochs = adam.epochs();
    st.lr = adam.lr();
    st.moments = adam.moments();
    st.cpu_s = cpu_base + double(std::clock() - cpu_start) / CLOCKS_PER_SEC;
    save_state(state_path, st);
    last_ckpt = std::chrono::steady_clock::now();
  };
  // The frozen mask net runs with its running statistics; with --freeze-bn so does the trained
  // net's BatchNorm (fixed statistics, not updated; its affine weights still learn).
  auto train_mode = [&] {
    mask.set_training(!pose_stage && !spec.freeze_bn);
    pose.set_training(pose_stage && !spec.freeze_bn);
  };
  // The validation windows are fixed for the run: built once (inputs behind the frozen mask
  // net, targets), scored in eval mode at every epoch's end.
  std::vector<std::unique_ptr<BatchBuilder>> val_batches;
  auto build_validation = [&] {
    // The split's recordings in turn, each window at a seeded time: the training stream's
    // cursors (8 open recordings, 8 windows per visit) drew all 48 validation windows from at
    // most 8 of the split's recordings, and the best epoch was picked on that narrow sample.
    sim::WindowStreamOptions vso = so;
    set_window(vso, cfg.window);
    vso.cursors = 1;
    vso.windows_per_visit = 1;
    vso.spread = true;
    WindowSource vs(val_scenes, val_files, spec.seed ^ 0x7a11da7eull, vso);
    constexpr int kPer = 4;
    mask.set_training(false);
    std::set<std::string> sources;
    sim::SimWindow w;
    for (int i = 0; i < spec.val_windows; i += kPer) {
      const int n = std::min(kPer, spec.val_windows - i);
      val_batches.push_back(std::make_unique<BatchBuilder>(cfg, n, builder.source(), lead));
      for (int k = 0; k < n; ++k) {
        vs.next(w);
        sources.insert(w.scene);
        const auto reuse = reuse_of(kValReuse + std::uint64_t(i + k));
        const Similarity zoom = framing_similarity(w, lead, cfg.window);
        val_batches.back()->add(w, mask, nullptr, spec.frame_zoom ? &zoom : nullptr, false, reuse ? &*reuse : nullptr);
      }
    }
    if (!val_files.empty())
      err << "validation: " << spec.val_windows << " windows from " << sources.size() << " of " << val_files.size()
          << " recordings\n";
  };
  struct ValScore {
    double loss = 0, mpjpe_mm = -1;
    std::array<double, 3> mask_iou{-1, -1, -1};  // at sigmoid > kCuts: is yelan run's cut (the first) well placed?
  };
  static constexpr std::array<float, 3> kCuts{input::kMaskCut, 0.3f, 0.5f};
  // What a validation adds to its log line: MPJPE (pose stage) or the mask IoU at every cut.
  auto score_text = [](const ValScore& v) {
    std::string t;
    if (v.mpjpe_mm >= 0) t += ", validation MPJPE " + std::to_string(int(std::lround(v.mpjpe_mm))) + " mm";
    if (v.mask_iou[0] >= 0) {
      t += ", validation mask IoU " + std::to_string(v.mask_iou[0]).substr(0, 5) + " (at sigmoid > " +
           std::to_string(kCuts[0]).substr(0, 3) + "; ";
      for (std::size_t k = 1; k < kCuts.size(); ++k)
        t += (k > 1 ? ", " : "") + std::to_string(kCuts[k]).substr(0, 3) + ": " + std::to_string(v.mask_iou[k]).substr(0, 5);
      t += ")";
    }
    return t;
  };
  // Mean loss of the net in eval mode over the validation windows, and what a reader
  // understands: for the pose stage MPJPE in mm (paper protocol), for the mask stage the IoU
  // of the current mask, cut where yelan run cuts it, against the true one.
  auto validate = [&] {
    if (val_batches.empty()) build_validation();
    mask.set_training(false);
    pose.set_training(false);
    double sum = 0;
    PoseMetrics metrics;
    int windows = 0;
    std::array<double, 3> inter{}, uni{};
    std::vector<float> keep;
    for (const auto& vb : val_batches) {
      const Batch& b = vb->batch();
      const int nw = b.frames / cfg.window;
      if (pose_stage) {
        pose.forward(b.input.act, cfg.window);
        std::vector<PoseNet::StageGrads> dheat;
        std::vector<layers::Floats> store;
        sum += hpe_loss(pose, cfg.stages, b.target.data(), b.valid.data(), dheat, store, swap_group).total * nw;
        const std::vector<float>& jn = pose.joints();
        for (int f = 0; f < b.frames; ++f)
          metrics.add(predicted_pose_mm(b, jn, f), b.truth_mm[std::size_t(f)], valid_joints(b, f));
      } else {
        mask.forward(b.input.act);
        layers::Floats dm(mask.masks().floats());
        std::vector<float> ds;
        sum += mask_loss(mask, b.labels.act, {dm.data(), mask.masks().n, mask.masks().c, mask.masks().h, mask.masks().w}, ds).total * nw;
        const layers::Act& m = mask.masks();
        for (int i = 0; i < m.n; ++i) {
          const float* truth = b.labels.act.data + std::size_t(i) * m.cb() * m.pixels() * 16;
          for (std::size_t k = 0; k < kCuts.size(); ++k) {
            input::mask_cut(m, i, 0, keep, kCuts[k]);
            for (std::size_t p = 0; p < keep.size(); ++p) {
              const bool pr = keep[p] > 0, tr = truth[p * 16] > 0.5f;
              inter[k] += pr && tr;
              uni[k] += pr || tr;
            }
          }
        }
      }
      windows += nw;
    }
    train_mode();
    ValScore v;
    v.loss = sum / windows;
    if (pose_stage) v.mpjpe_mm = metrics.scores().mpjpe_mm;
    if (!pose_stage)  // nobody in any window, and no mask: all right
      for (std::size_t k = 0; k < kCuts.size(); ++k) v.mask_iou[k] = uni[k] > 0 ? inter[k] / uni[k] : 1;
    return v;
  };

  train_mode();
  double loss = 0, grad_norm = 0;
  TrainResult result;
  const StopOnSignal stop;
  if (st.bad_epochs >= spec.patience) {
    result.early_stopped = true;
    err << "this run had already stopped early (no better validation loss for " << spec.patience << " epochs)\n";
  }
  if (spec.validate_start && st.step == 0 && !result.early_stopped) {
    // The start's own score on the same windows, so a fine-tune's first epoch has a baseline.
    // Logged only: best.h5 stays the best of the trained epochs.
    const ValScore v = validate();
    const double cpu = double(std::clock() - cpu_start) / CLOCKS_PER_SEC + cpu_base;
    write_log_row(log, {0, adam.epochs(), -1, v.loss, cosine ? scheduled_lr(spec, 0) : adam.lr(), 0, 0,
                        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), v.mpjpe_mm, cpu,
                        v.mask_iou[0]});
    err << "step 0 (the start): validation " << v.loss << score_text(v) << "\n";
  }
  const std::int64_t first_step = st.step;
  double data_s = 0, step_s = 0;  // since the last epoch line: building batches, whole steps
  std::int64_t swap_groups = 0, swapped = 0;  // --swap-loss: windows scored, and of them traded, since then
  // A batch's window buffers serve every batch: their frames' TORE read-outs (2 MB each at
  // the sensor's size) allocated afresh each time cost the kernel's page clearing and faults.
  // The windows are read from their recordings in parallel, then batched in order.
  std::vector<sim::SimWindow> windows(std::size_t(spec.batch));
  while (st.step < spec.steps && !result.early_stopped) {
    const auto t0 = std::chrono::steady_clock::now();
    builder.clear();
    stream.next_batch(windows, spec.read_threads > 0 ? spec.read_threads : threads());
    for (int b = 0; b < spec.batch; ++b) {
      const sim::SimWindow& w = windows[std::size_t(b)];
      sim::Rng occ(spec.seed, 0x0cc1u + std::uint64_t(st.step) * 4096 + std::uint64_t(b));
      // Its own stream, so the occluders of a run with --warp are those of one without.
      sim::Rng wr(spec.seed, 0x3a9fu + std::uint64_t(st.step) * 4096 + std::uint64_t(b));
      const Similarity warp =
          spec.frame_zoom ? framing_similarity(w, lead, cfg.window) : draw_similarity(wr, cfg.sensor_width, cfg.sensor_height);
      sim::Rng fr(spec.seed, 0xf11bu + std::uint64_t(st.step) * 4096 + std::uint64_t(b));
      const bool flip = spec.flip && fr.uniform() < 0.5;
      const auto reuse = reuse_of(kReuseStream + std::uint64_t(st.step) * 4096 + std::uint64_t(b));
      builder.add(w, mask, spec.occlusion ? &occ : nullptr, spec.warp || spec.frame_zoom ? &warp : nullptr, flip, reuse ? &*reuse : nullptr);
    }
    const double built = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    data_s += built;
    result.data_s += built;
    const Batch& batch = builder.batch();
    adam.zero_grad();
    if (cosine) adam.set_lr(scheduled_lr(spec, st.step));
    if (pose_stage) {
      pose.forward(batch.input.act, cfg.window);
      std::vector<PoseNet::StageGrads> dheat;
      std::vector<layers::Floats> store;
      const HpeLoss l = hpe_loss(pose, cfg.stages, batch.target.data(), batch.valid.data(), dheat, store, swap_group);
      loss = l.total;
      swap_groups += l.groups;
      swapped += l.swapped;
      pose.backward(batch.input.act, dheat, nullptr);
    } else {
      mask.forward(batch.input.act);
      layers::Floats dm(mask.masks().floats());
      const layers::Act dmasks{dm.data(), mask.masks().n, mask.masks().c, mask.masks().h, mask.masks().w};
      std::vector<float> dscores;
      const std::vector<float> weights =
          spec.empty_weight == 1 ? std::vector<float>{} : nobody_weights(batch.labels.act, spec.empty_weight);
      loss = mask_loss(mask, batch.labels.act, dmasks, dscores, weights, spec.dice_weight, spec.mask_focus).total;
      mask.backward(batch.input.act, dmasks, dscores.data());
    }
    if (!std::isfinite(loss))  // the last checkpoint stays as it was: this step's BN statistics may be NaN
      throw std::runtime_error("loss is " + std::to_string(loss) + " at step " + std::to_string(st.step) +
                               "; the last checkpoint is kept");
    grad_norm = adam.step();
    (pose_stage ? static_cast<void>(pose.weights_changed()) : mask.weights_changed());
    ++st.step;
    const double dt = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    step_s += dt;
    result.step_s += dt;
    result.frames += std::int64_t(spec.batch) * tcfg.window;
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const double sps = spec.batch * tcfg.window / dt;
    double val = -1, val_mm = -1, val_iou = -1;
    std::string scores;
    const bool epoch_end = st.step % spec.steps_per_epoch == 0 || st.step == spec.steps;
    if (epoch_end) {
      const ValScore v = validate();
      val = v.loss, val_mm = v.mpjpe_mm, val_iou = v.mask_iou[0];
      scores = score_text(v);
      adam.end_epoch();
      if (cosine) adam.set_lr(scheduled_lr(spec, st.step));
      const double crit = pose_stage ? val_mm : val;  // pose: selected by validation MPJPE (mm)
      if (crit < st.best_val) {
        st.best_val = crit;
        st.bad_epochs = 0;
        weights::save_weights((fs::path(spec.out_dir) / "best.h5").string(), weights::weights_of(cfg, mp, pp));
      } else {
        ++st.bad_epochs;
      }
    }
    const double cpu = double(std::clock() - cpu_start) / CLOCKS_PER_SEC + cpu_base;
    write_log_row(log, {st.step, adam.epochs(), loss, val, adam.lr(), grad_norm, sps, wall, val_mm, cpu, val_iou});
    const double eta = wall / double(st.step - first_step) * double(spec.steps - st.step);
    if (spec.progress_tty)
      err << "\rstep " << st.step << "/" << spec.steps << "  epoch " << adam.epochs() << "  loss " << std::fixed
          << std::setprecision(4) << loss << "  lr " << std::scientific << std::setprecision(1) << adam.lr()
          << std::defaultfloat << "  " << std::setprecision(3) << sps << " samples/s  ETA " << eta_text(eta) << "   "
          << std::flush;
    if (epoch_end)
      err << (spec.progress_tty ? "\n" : "") << "epoch " << adam.epochs() << " step " << st.step << ": loss " << loss
          << ", validation " << val << " (best " << st.best_val << ")" << scores
          << (swap_groups ? ", " + std::to_string(std::lround(100.0 * double(swapped) / double(swap_groups))) + "% of windows traded" : "")
          << ", " << sps
          << " samples/s, lr " << adam.lr() << ", data " << std::lround(100 * data_s / std::max(step_s, 1e-9))
          << "% of step time\n";
    if (epoch_end) data_s = step_s = 0, swap_groups = swapped = 0;
    const double run_cpu = double(std::clock() - cpu_start) / CLOCKS_PER_SEC;
    const bool out_of_time =
        (spec.max_minutes > 0 && wall > spec.max_minutes * 60) || (spec.max_cpu_minutes > 0 && run_cpu > spec.max_cpu_minutes * 60);
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - last_ckpt).count() > spec.checkpoint_minutes * 60 ||
        out_of_time)
      checkpoint();
    if (epoch_end && st.bad_epochs >= spec.patience) {
      result.early_stopped = true;
      err << "early stop: no better validation loss for " << spec.patience << " epochs\n";
      break;
    }
    if (out_of_time) {
      err << "time limit reached at step " << st.step << " (checkpoint written; --resume continues)\n";
      break;
    }
    if (stop.signal()) {  // the checkpoint is written after the loop
      result.interrupted = stop.signal();
      err << (spec.progress_tty ? "\n" : "") << "interrupted at step " << st.step
          << " (checkpoint written; --resume continues exactly)\n";
      break;
    }
    if (spec.stop_at > 0 && st.step >= spec.stop_at && st.step < spec.steps) {
      err << "stopped at step " << st.step << " as asked (--resume continues)\n";
      break;
    }
  }
  checkpoint();
  weights::save_weights((fs::path(spec.out_dir) / "final.h5").string(), weights::weights_of(cfg, mp, pp));
  if (spec.progress_tty) err << "\n";
  result.steps = st.step;
  result.cpu_s = double(std::clock() - cpu_start) / CLOCKS_PER_SEC;
  result.last_loss = loss;
  result.best_val = st.best_val;
  return result;
}

}  // namespace yelan::train
