#include "benchmarks/train/bench_train.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <functional>
#include <iomanip>
#include <sstream>

#include "benchmarks/bench_util.h"
#include "camera/io/event_writer.h"
#include "camera/io/h5.h"
#include "camera/sim/presets.h"
#include "camera/sim/window_stream.h"
#include "engine/adam.h"
#include "engine/cli/output_path.h"
#include "engine/losses.h"
#include "engine/mask_net.h"
#include "engine/pose_net.h"
#include "engine/subprocess.h"
#include "camera/sim/recording_windows.h"
#include "engine/train/batch.h"
#include "engine/train/trainer.h"
#include "weights_tools/network_io.h"
#include "weights_tools/weights_file.h"

#ifndef YELAN_SOURCE_DIR
#define YELAN_SOURCE_DIR "."
#endif

namespace yelan::bench {
namespace {

namespace sim = camera::sim;
namespace h5 = camera::h5;
namespace fs = std::filesystem;

constexpr std::uint64_t kSeed = 1;  // the trainer's default --seed: its initial weights and scenes
constexpr int kWarmup = 2;          // untimed steps first (both sides): buffers, packed weights

// The batches of one stage, kept in our blocked layout so the timed loop copies nothing.
struct StageData {
  std::string stage;
  int frames = 0;  // per batch: windows x the config's window
  std::vector<layers::Floats> input, labels;
  std::vector<std::vector<float>> target, valid;
};

struct Row {
  std::string stage;
  int threads = 1, frames = 0;
  double ours_ms = 0, ours_loss = 0;
  bool torch = false;
  double torch_ms = 0, torch_loss = 0;
  double ours_sps() const { return 1e3 * frames / ours_ms; }
  double torch_sps() const { return 1e3 * frames / torch_ms; }
};

// "train" / "test" (the grid splits) or comma-separated preset names.
std::vector<sim::SimSpec> scenes_of(const std::string& text) {
  const auto names = text == "train" || text == "test" ? sim::grid_presets(text) : cli::split_list(text);
  if (names.empty()) throw cli::UsageError("--sim: no scenes in '" + text + "'");
  std::vector<sim::SimSpec> out;
  for (const auto& n : names) {
    try {
      out.push_back(sim::preset_spec(n));
    } catch (const std::exception& e) {
      throw cli::UsageError(std::string("--sim: ") + e.what());
    }
  }
  return out;
}

// `batches` batches of `windows` windows each, streamed and assembled as train() does
// (same stream options, seed and mask source; no occlusion).
StageData build_batches(const ModelConfig& cfg, const std::string& stage, int windows, int batches,
                        const std::vector<sim::SimSpec>& scenes) {
  const bool pose = stage == "pose";
  sim::WindowStreamOptions so;
  so.frame_hz = 50;
  so.window = cfg.window + (pose ? 0 : cfg.n_masks - 1);
  so.warmup_s = 0.1;
  so.scene_s = so.warmup_s + so.window / so.frame_hz + 1e-6;
  so.shuffle = true;
  so.counts = cfg.representation == "counts";
  sim::SimWindowStream stream(scenes, kSeed, so);
  train::BatchBuilder builder(cfg, windows, pose ? train::MaskSource::truth : train::MaskSource::none);
  MaskNet unused(cfg);  // the builder runs a mask net for MaskSource::net only
  StageData d;
  d.stage = stage;
  d.frames = windows * cfg.window;
  auto copy = [](const layers::Act& a) {
    layers::Floats f(a.floats());
    std::memcpy(f.data(), a.data, a.floats() * sizeof(float));
    return f;
  };
  for (int b = 0; b < batches; ++b) {
    builder.clear();
    for (int w = 0; w < windows; ++w) {
      sim::SimWindow win;
      stream.next(win);
      builder.add(win, unused, nullptr);
    }
    const train::Batch& bt = builder.batch();
    d.input.push_back(copy(bt.input.act));
    if (pose) {
      d.target.push_back(bt.target);
      d.valid.push_back(bt.valid);
    } else {
      d.labels.push_back(copy(bt.labels.act));
    }
  }
  return d;
}

// One frame range of a blocked activation as plain NCHW.
std::vector<float> nchw(const float* blocked, int n, int c, int h, int w) {
  const layers::Act a{const_cast<float*>(blocked), n, c, h, w};
  std::vector<float> out(std::size_t(n) * c * a.pixels());
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < c; ++k)
      for (std::size_t p = 0; p < a.pixels(); ++p)
        out[(std::size_t(i) * c + k) * a.pixels() + p] = blocked[((std::size_t(i) * a.cb() + k / 16) * a.pixels() + p) * 16 + k % 16];
  return out;
}

// A float32 dataset whose first dimension is the batch, written one batch at a time.
void write_batches(hid_t loc, const std::string& name, const std::vector<hsize_t>& dims,
                   const std::function<std::vector<float>(int)>& batch) {
  h5::H5Id space = h5::check(H5Screate_simple(int(dims.size()), dims.data(), nullptr), "dataspace for " + name);
  h5::H5Id props = h5::untimed_dataset_props();
  h5::H5Id ds = h5::check(H5Dcreate2(loc, name.c_str(), H5T_NATIVE_FLOAT, space.get(), H5P_DEFAULT, props.get(), H5P_DEFAULT),
                          "create " + name);
  std::vector<hsize_t> one = dims, start(dims.size(), 0);
  one[0] = 1;
  h5::H5Id mem = h5::check(H5Screate_simple(int(one.size()), one.data(), nullptr), "dataspace for " + name);
  for (hsize_t b = 0; b < dims[0]; ++b) {
    start[0] = b;
    h5::check(H5Sselect_hyperslab(space.get(), H5S_SELECT_SET, start.data(), nullptr, one.data(), nullptr), "select " + name);
    const std::vector<float> v = batch(int(b));
    h5::check(H5Dwrite(ds.get(), H5T_NATIVE_FLOAT, mem.get(), space.get(), H5P_DEFAULT, v.data()), "write " + name);
  }
}

// The pose stage's batches are masked by the true masks: with pose.outside_input they hold
// the input twice (inside and outside the mask).
int input_channels(const ModelConfig& cfg, const StageData& d) {
  return d.stage == "pose" ? cfg.pose_channels() : cfg.channels;
}

// Groups /pose and/or /mask: input [batches, frames, C, H, W]; pose: target [.., frames, J, 3],
// valid [.., frames, J]; mask: labels [.., frames, N, H, W]. Written to a temporary and renamed.
void write_data(const std::string& path, const ModelConfig& cfg, int windows, const std::vector<StageData>& stages) {
  h5::silence_errors();
  camera::TempFile tmp(path);
  {
    h5::H5Id f = h5::create_file(tmp.path());
    h5::write_attr_string(f.get(), "format", "yelan-train-bench");
    h5::write_attr_string(f.get(), "config", cfg.json);
    h5::write_attr_i64(f.get(), "windows_per_batch", windows);
    h5::write_attr_i64(f.get(), "seed", std::int64_t(kSeed));
    const hsize_t H = hsize_t(cfg.height()), W = hsize_t(cfg.width()), J = hsize_t(cfg.joints);
    for (const StageData& d : stages) {
      h5::H5Id g = h5::create_group(f.get(), d.stage);
      const int c = input_channels(cfg, d);
      const hsize_t B = d.input.size(), n = hsize_t(d.frames);
      write_batches(g.get(), "input", {B, n, hsize_t(c), H, W},
                    [&](int b) { return nchw(d.input[b].data(), d.frames, c, cfg.height(), cfg.width()); });
      if (d.stage == "pose") {
        write_batches(g.get(), "target", {B, n, J, 3}, [&](int b) { return d.target[b]; });
        write_batches(g.get(), "valid", {B, n, J}, [&](int b) { return d.valid[b]; });
      } else {
        write_batches(g.get(), "labels", {B, n, hsize_t(cfg.n_masks), H, W},
                      [&](int b) { return nchw(d.labels[b].data(), d.frames, cfg.n_masks, cfg.height(), cfg.width()); });
      }
    }
  }
  tmp.commit();
}

// Both networks as train() starts them (same seeds), so the weights file written from one
// pair is what every timed run starts from.
struct Networks {
  MaskNet mask;
  PoseNet pose;
  layers::ParamList mp, pp;
  explicit Networks(const ModelConfig& cfg) : mask(cfg), pose(cfg) {
    mask.params(mp);
    pose.params(pp);
    mask.init(kSeed * 2 + 1);
    pose.init(kSeed * 2 + 2);
    mask.weights_changed();
    pose.weights_changed();
  }
};

// `steps` timed training steps after kWarmup, cycling over the batches; the loss of the
// first step is the loss at the initial weights.
Row time_stage(const ModelConfig& cfg, const StageData& d, int steps, int threads, std::ostream& err) {
  set_threads(threads);
  const bool is_pose = d.stage == "pose";
  Networks nets(cfg);
  MaskNet& mask = nets.mask;
  PoseNet& pose = nets.pose;
  mask.set_training(!is_pose);
  pose.set_training(is_pose);
  Adam adam(is_pose ? nets.pp : nets.mp, AdamOptions{});
  const int batches = int(d.input.size());
  auto step = [&](int k) {
    const int b = k % batches;
    const layers::Act x{const_cast<float*>(d.input[b].data()), d.frames, input_channels(cfg, d), cfg.height(), cfg.width()};
    double loss;
    adam.zero_grad();
    if (is_pose) {
      pose.forward(x, cfg.window);
      std::vector<PoseNet::StageGrads> dheat;
      std::vector<layers::Floats> store;
      loss = hpe_loss(pose, cfg.stages, d.target[b].data(), d.valid[b].data(), dheat, store).total;
      pose.backward(x, dheat, nullptr);
    } else {
      mask.forward(x);
      layers::Floats dm(mask.masks().floats());
      const layers::Act dmasks{dm.data(), mask.masks().n, mask.masks().c, mask.masks().h, mask.masks().w};
      const layers::Act labels{const_cast<float*>(d.labels[b].data()), d.frames, cfg.n_masks, cfg.height(), cfg.width()};
      std::vector<float> dscores;
      loss = mask_loss(mask, labels, dmasks, dscores).total;
      mask.backward(x, dmasks, dscores.data());
    }
    adam.step();
    is_pose ? pose.weights_changed() : mask.weights_changed();
    return loss;
  };
  Row r;
  r.stage = d.stage;
  r.threads = threads;
  r.frames = d.frames;
  r.ours_loss = step(0);
  for (int k = 1; k < kWarmup; ++k) step(k);
  std::vector<double> ms;
  for (int i = 0; i < steps; ++i) {
    const auto t0 = std::chrono::steady_clock::now();
    step(kWarmup + i);
    ms.push_back(std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());
  }
  std::nth_element(ms.begin(), ms.begin() + ms.size() / 2, ms.end());
  r.ours_ms = ms[ms.size() / 2];
  err << "  ours " << d.stage << " x" << threads << ": " << std::fixed << std::setprecision(1) << r.ours_ms << " ms/step, "
      << r.ours_sps() << " samples/s\n" << std::defaultfloat;
  return r;
}

// PyTorch on the same file and weights (benchmarks/torch/train_bench.py), after ours, so the
// two thread pools never share the cores.
void torch_times(const std::string& data, const std::string& weights, const std::vector<std::string>& stages,
                 const std::vector<int>& threads, int steps, std::vector<Row>& rows, std::ostream& err) {
  if (!reference_python_imports("torch, h5py")) {
    err << "no PyTorch comparison: /usr/bin/python3 cannot import torch and h5py (scripts/setup-debian --reference)\n";
    return;
  }
  // Relative paths are the caller's, so the absolute forms go to a script run from the source tree.
  Program py({"/usr/bin/python3", "benchmarks/torch/train_bench.py", "--data", fs::absolute(data).string(), "--weights",
              fs::absolute(weights).string(), "--steps", std::to_string(steps), "--warmup", std::to_string(kWarmup),
              "--stages", comma_list(stages), "--threads", comma_list(threads)});
  py.cwd = YELAN_SOURCE_DIR;
  py.capture_stdout = true;
  py.show_stderr = true;
  const ProgramResult res = run_program(py);
  if (!res.started) {
    err << "no PyTorch comparison: " << res.why() << "\n";
    return;
  }
  std::istringstream lines(res.out);
  for (std::string text; std::getline(lines, text);) {  // "train STAGE THREADS MS_PER_STEP INITIAL_LOSS"
    const char* line = text.c_str();
    char stage[16];
    int t;
    double ms, loss;
    if (std::sscanf(line, "train %15s %d %lf %lf", stage, &t, &ms, &loss) != 4) continue;
    for (Row& r : rows)
      if (r.stage == stage && r.threads == t) r.torch = true, r.torch_ms = ms, r.torch_loss = loss;
  }
  if (!res.ok()) err << "benchmarks/torch/train_bench.py failed (" << res.why() << "): see its message above\n";
}

// The weights file beside the data: DATA.h5 -> DATA.weights.h5.
std::string weights_path_for(const std::string& data) {
  const std::string stem = data.size() > 3 && data.ends_with(".h5") ? data.substr(0, data.size() - 3) : data;
  return stem + ".weights.h5";
}

struct ScratchDir {  // removed with its files unless the data is kept
  fs::path p;
  ~ScratchDir() {
    std::error_code ec;
    if (!p.empty()) fs::remove_all(p, ec);
  }
};

std::string num(double v, bool present) {
  if (!present || !std::isfinite(v)) return "null";
  std::ostringstream o;
  o << std::setprecision(9) << v;
  return o.str();
}

void print_json(const std::string& config, int windows, const std::vector<Row>& rows, std::ostream& out) {
  out << "[\n";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const Row& r = rows[i];
    out << "  {\"config\": \"" << config << "\", \"stage\": \"" << r.stage << "\", \"threads\": " << r.threads
        << ", \"batch\": " << windows << ", \"frames_per_step\": " << r.frames << ", \"ours_ms_per_step\": " << num(r.ours_ms, true)
        << ", \"ours_samples_per_s\": " << num(r.ours_sps(), true) << ", \"torch_ms_per_step\": " << num(r.torch_ms, r.torch)
        << ", \"torch_samples_per_s\": " << num(r.torch_sps(), r.torch)
        << ", \"ratio\": " << num(r.ours_sps() / r.torch_sps(), r.torch) << ", \"initial_loss\": " << num(r.ours_loss, true)
        << ", \"torch_initial_loss\": " << num(r.torch_loss, r.torch) << "}" << (i + 1 < rows.size() ? "," : "") << "\n";
  }
  out << "]\n";
}

void print_table(const std::string& config, const std::vector<Row>& rows, std::ostream& out) {
  out << "config    stage threads frames/step  ours ms/step  ours samples/s  torch ms/step  torch samples/s  ours/torch"
         "  initial loss ours / torch\n";
  for (const Row& r : rows) {
    char line[320];
    std::snprintf(line, sizeof line, "%-9s %-5s %7d %11d %13.1f %15.2f", config.c_str(), r.stage.c_str(), r.threads, r.frames,
                  r.ours_ms, r.ours_sps());
    out << line;
    if (r.torch)
      std::snprintf(line, sizeof line, " %14.1f %16.2f %10.2fx  %.6g / %.6g", r.torch_ms, r.torch_sps(), r.ours_sps() / r.torch_sps(),
                    r.ours_loss, r.torch_loss);
    else
      std::snprintf(line, sizeof line, " %14s %16s %11s  %.6g / -", "-", "-", "-", r.ours_loss);
    out << line << "\n";
  }
}

// The whole trainer, data included: `steps` steps of the pose stage at one thread reading
// the dataset on disk (the default: batch 8, 5 s of TORE history), against the issue-7
// path (windows simulated afresh, batch 1) on the same config, in the same run.
int pipeline_bench(const ModelConfig& cfg, const std::string& dir, int steps, bool json, std::ostream& out, std::ostream& err) {
  struct Side {
    std::string name;
    train::TrainResult r;
  };
  std::vector<Side> sides;
  ScratchDir scratch;
  scratch.p = fs::temp_directory_path() / ("yelan-bench-pipeline-" + std::to_string(::getpid()));
  fs::create_directories(scratch.p);
  const int saved = yelan::threads();
  set_threads(1);
  for (const bool disk : {true, false}) {
    train::TrainSpec t;
    t.stage = "pose";
    t.cfg = cfg;
    if (disk) {
      const bool dataset = fs::is_directory(fs::path(dir) / "train") && fs::is_directory(fs::path(dir) / "val");
      if (dataset) {
        t.data = camera::sim::list_recordings((fs::path(dir) / "train").string());
        t.val_data = camera::sim::list_recordings((fs::path(dir) / "val").string());
      } else {
        camera::sim::split_by_recording(camera::sim::list_recordings(dir), t.data, t.val_data);
      }
      t.batch = 8;
    } else {
      t.scenes = scenes_of("train");
      t.batch = 1;
    }
    t.steps = disk ? steps : std::max(2, steps / 2);
    t.steps_per_epoch = 1 << 30;  // one validation, at the end, of one window
    t.val_windows = 1;
    t.warmup_steps = 0;
    t.checkpoint_minutes = 1e6;
    t.out_dir = (scratch.p / (disk ? "disk" : "sim")).string();
    err << (disk ? "training from " + dir : std::string("training from the simulator stream")) << ": " << t.steps
        << " steps of " << t.batch << " x " << cfg.window << " frames at one thread\n";
    std::ostringstream quiet;
    sides.push_back({disk ? "disk dataset, batch 8, 5 s history" : "simulator stream, batch 1 (issue 7)", train::train(t, quiet)});
  }
  set_threads(saved);
  const auto sps = [](const train::TrainResult& r) { return r.frames / std::max(r.step_s, 1e-9); };
  const auto per_cpu = [](const train::TrainResult& r) { return r.frames / std::max(r.cpu_s, 1e-9); };
  const double ratio = per_cpu(sides[0].r) / per_cpu(sides[1].r);
  if (json) {
    out << "{\"config\": \"" << cfg.name << "\", \"cpu\": \"" << cpu_name() << "\", \"rows\": [";
    for (std::size_t i = 0; i < sides.size(); ++i)
      out << (i ? ", " : "") << "{\"data\": \"" << sides[i].name << "\", \"samples_per_s\": " << sps(sides[i].r)
          << ", \"samples_per_cpu_s\": " << per_cpu(sides[i].r) << ", \"data_share\": "
          << sides[i].r.data_s / std::max(sides[i].r.step_s, 1e-9) << ", \"frames\": " << sides[i].r.frames << "}";
    out << "], \"ratio_per_cpu_s\": " << ratio << "}\n";
    return 0;
  }
  out << "training data pipeline, " << cfg.name << ", one thread, " << cpu_name() << "\n";
  for (const Side& s : sides)
    out << std::fixed << std::setprecision(1) << "  " << std::left << std::setw(40) << s.name << std::right << std::setw(8)
        << sps(s.r) << " samples/s  " << std::setw(8) << per_cpu(s.r) << " per CPU-s  data " << std::setprecision(0)
        << 100 * s.r.data_s / std::max(s.r.step_s, 1e-9) << "% of step time\n";
  out << std::setprecision(2) << "  disk / simulator, samples per CPU-second: " << ratio << "x\n";
  return 0;
}

}  // namespace

int run_train_bench(const std::vector<std::string>& argv, std::ostream& out, std::ostream& err) {
  cli::Args args("bench train", argv, {"--config", "--stage", "--batch", "--batches", "--steps", "--threads-list", "--sim", "--keep-data", "--data"},
                 {"--json", "--no-torch"});
  args.expect_positionals(0, 0);
  const std::string config = args.value_or("--config", "small");
  ModelConfig cfg;
  try {
    cfg = load_model_config(config);
  } catch (const ConfigError& e) {
    throw cli::UsageError(e.what());
  }
  if (const auto dir = args.value("--data")) {
    try {
      return pipeline_bench(cfg, *dir, args.int_value_or("--steps", 20, 2, 1 << 20), args.flag("--json"), out, err);
    } catch (const std::runtime_error& e) {
      throw cli::UsageError(std::string("--data: ") + e.what());
    }
  }
  const std::string which = args.value_or("--stage", "both");
  if (which != "pose" && which != "mask" && which != "both") throw cli::UsageError("--stage must be pose, mask or both");
  const std::vector<std::string> stages = which == "both" ? std::vector<std::string>{"pose", "mask"} : std::vector<std::string>{which};
  const int windows = args.int_value_or("--batch", 1, 1, 1024);
  const int batches = args.int_value_or("--batches", 4, 1, 1024);
  const int steps = args.int_value_or("--steps", 20, 1, 1 << 20);
  const std::vector<int> threads = threads_list(args, "1");
  const auto scenes = scenes_of(args.value_or("--sim", "train"));
  const bool torch = !args.flag("--no-torch");
  const auto keep = args.value("--keep-data");
  if (keep) cli::check_output("--keep-data", *keep, {config});

  std::vector<StageData> data;
  for (const auto& s : stages) {
    err << "building " << batches << " " << s << " batches of " << windows << " x " << cfg.window << " frames (" << cfg.name
        << ")\n";
    data.push_back(build_batches(cfg, s, windows, batches, scenes));
  }
  // The data and the initial weights, for PyTorch (and for the user with --keep-data).
  ScratchDir scratch;
  std::string data_path;
  if (keep) {
    data_path = fs::absolute(*keep).string();
  } else if (torch) {
    scratch.p = fs::temp_directory_path() / ("yelan-bench-train-" + std::to_string(::getpid()));
    fs::create_directories(scratch.p);
    data_path = (scratch.p / "batches.h5").string();
  }
  const std::string weights_path = weights_path_for(data_path);
  if (!data_path.empty()) {
    write_data(data_path, cfg, windows, data);
    const Networks initial(cfg);
    weights::save_weights(weights_path, weights::weights_of(cfg, initial.mp, initial.pp));
    if (keep) err << "kept " << data_path << " and its initial weights " << weights_path << "\n";
  }

  std::vector<Row> rows;
  const int saved = yelan::threads();
  for (const StageData& d : data)
    for (int t : threads) rows.push_back(time_stage(cfg, d, steps, t, err));
  set_threads(saved);
  if (torch) {
    torch_times(data_path, weights_path, stages, threads, steps, rows, err);
    // Same weights, same batch, same loss: anything else means the two do not train the same thing.
    for (const Row& r : rows)
      if (r.torch && std::abs(r.ours_loss - r.torch_loss) > 1e-3 * std::abs(r.torch_loss))
        err << "warning: " << r.stage << " x" << r.threads << ": initial loss " << r.ours_loss << " here, " << r.torch_loss
            << " in PyTorch (relative difference above 1e-3)\n";
  }
  if (args.flag("--json"))
    print_json(cfg.name, windows, rows, out);
  else
    print_table(cfg.name, rows, out);
  return 0;
}

}  // namespace yelan::bench
