#include "benchmarks/networks/bench_networks.h"

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <map>
#include <random>
#include <sstream>
#include <unistd.h>

#include "benchmarks/bench_util.h"
#include "benchmarks/kernels/timing.h"
#include "engine/cli/args.h"
#include "engine/losses.h"
#include "engine/mask_net.h"
#include "engine/pose_net.h"
#include "engine/threads.h"
#include "kernels/cpu.h"

#ifndef YELAN_SOURCE_DIR
#define YELAN_SOURCE_DIR "."
#endif

namespace yelan::bench {
namespace {

struct Row {
  std::string config, mode;
  int threads, frames;
  double ms_per_frame, peak_mb;
  double torch_ms_per_frame = 0;
};

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  for (std::string item; std::getline(ss, item, ',');) out.push_back(item);
  return out;
}

// One config: inference and training per frame; memory held at peak by the layers.
void bench_config(const ModelConfig& cfg, int frames, int threads, int reps, std::vector<Row>& rows, std::ostream& err) {
  set_threads(threads);
  layers::reset_floats_peak();
  const std::size_t base = layers::floats_live_bytes();
  MaskNet mask(cfg);
  PoseNet pose(cfg);
  mask.init(1);
  pose.init(2);
  const int pc = cfg.pose_channels();  // pose.outside_input: stage 1 reads the first channels of the same block
  layers::Floats xb(std::size_t(frames) * ((pc + 15) / 16) * cfg.height() * cfg.width() * 16);
  std::mt19937 rng(3);
  for (std::size_t i = 0; i < xb.size(); ++i) xb[i] = std::uniform_real_distribution<float>(0, 1)(rng);
  // padding lanes back to zero
  const layers::Act x{xb.data(), frames, pc, cfg.height(), cfg.width()};
  const layers::Act x_mask{xb.data(), frames, cfg.channels, cfg.height(), cfg.width()};
  for (int n = 0; n < frames; ++n)
    for (int c = pc; c < x.cb() * 16; ++c)
      for (std::size_t p = 0; p < x.pixels(); ++p) xb[((std::size_t(n) * x.cb() + c / 16) * x.pixels() + p) * 16 + c % 16] = 0;

  mask.set_training(false);
  pose.set_training(false);
  auto infer = [&] {
    layers::NoGrad no_grad;  // inference as deployed: BN folded into the convolutions
    mask.forward(x_mask);
    pose.forward(x, frames);
  };
  const double s_inf = median_seconds_per_call(infer, reps, 0.0);
  const double peak_inf = double(layers::floats_peak_bytes() - base) / 1e6;
  rows.push_back({cfg.name, "inference", threads, frames, 1e3 * s_inf / frames, peak_inf});
  err << "  " << cfg.name << " inference x" << threads << ": " << std::fixed << std::setprecision(2) << 1e3 * s_inf / frames
      << " ms/frame\n";

  mask.set_training(true);
  pose.set_training(true);
  std::vector<float> target(std::size_t(frames) * cfg.joints * 3, 0.1f), valid(std::size_t(frames) * cfg.joints, 1.f);
  layers::Floats lab(mask.masks().floats());
  const layers::Act labels{lab.data(), frames, cfg.n_masks, cfg.height(), cfg.width()};
  layers::Floats dm(mask.masks().floats());
  const layers::Act dmasks{dm.data(), frames, cfg.n_masks, cfg.height(), cfg.width()};
  std::vector<float> dscores;
  std::vector<PoseNet::StageGrads> dheat;
  std::vector<layers::Floats> store;
  auto train = [&] {
    mask.forward(x_mask);
    mask_loss(mask, labels, dmasks, dscores);
    mask.backward(x_mask, dmasks, dscores.data());
    pose.forward(x, frames);
    hpe_loss(pose, cfg.stages, target.data(), valid.data(), dheat, store);
    pose.backward(x, dheat, nullptr);
  };
  const double s_train = median_seconds_per_call(train, reps, 0.0);
  const double peak_train = double(layers::floats_peak_bytes() - base) / 1e6;
  rows.push_back({cfg.name, "training", threads, frames, 1e3 * s_train / frames, peak_train});
  err << "  " << cfg.name << " training x" << threads << ": " << 1e3 * s_train / frames << " ms/frame\n";
}

// PyTorch on the same configs and windows (benchmarks/torch/net_bench.py), after ours.
void torch_times(const std::vector<std::pair<std::string, int>>& configs, const std::vector<int>& threads, int reps,
                 std::vector<Row>& rows, std::ostream& err) {
  if (!reference_python_imports("torch")) {
    err << "no PyTorch comparison: /usr/bin/python3 cannot import torch\n";
    return;
  }
  Program py({"/usr/bin/python3", "benchmarks/torch/net_bench.py", "--reps", std::to_string(reps), "--threads",
              comma_list(threads)});
  // Config names resolve against the source tree, where the script runs; a config file the
  // caller named by a relative path goes as an absolute one.
  for (const auto& [c, frames] : configs) {
    std::error_code ec;
    const bool file = std::filesystem::is_regular_file(c, ec);
    py.argv.push_back((file ? std::filesystem::absolute(c).string() : c) + ":" + std::to_string(frames));
  }
  py.cwd = YELAN_SOURCE_DIR;
  py.capture_stdout = true;
  py.show_stderr = true;
  const ProgramResult res = run_program(py);
  if (!res.ok()) err << "benchmarks/torch/net_bench.py failed (" << res.why() << ")\n";
  std::istringstream lines(res.out);
  for (std::string text; std::getline(lines, text);) {  // "config mode threads ms_per_frame"
    const char* line = text.c_str();
    char cfg[128], mode[32];
    int t;
    double ms;
    if (std::sscanf(line, "%127s %31s %d %lf", cfg, mode, &t, &ms) != 4) continue;
    for (Row& r : rows)
      if (r.config == cfg && r.mode == mode && r.threads == t) r.torch_ms_per_frame = ms;
  }
}

}  // namespace

int run_networks_bench(const std::vector<std::string>& argv, std::ostream& out, std::ostream& err) {
  cli::Args args("bench networks", argv, {"--configs", "--threads-list", "--window", "--reps"}, {"--json", "--no-torch"});
  args.expect_positionals(0, 0);
  const auto names = split(args.value_or("--configs", "paper,small,tiny"));
  std::vector<int> threads;
  for (const auto& t : split(args.value_or("--threads-list", "1,2"))) {
    auto n = parse_thread_count(t);
    if (!n) throw cli::UsageError("--threads-list: '" + t + "' is not a thread count");
    threads.push_back(*n);
  }
  const int window = args.int_value_or("--window", 0, 0, 64);  // 0: the config's own
  const int reps = args.int_value_or("--reps", 3, 1, 100);
  std::vector<Row> rows;
  std::vector<std::pair<std::string, int>> used;
  const int saved = yelan::threads();
  for (const auto& name : names) {
    ModelConfig cfg;
    try {
      cfg = load_model_config(name);
    } catch (const ConfigError& e) {
      throw cli::UsageError(e.what());
    }
    const int frames = window ? window : cfg.window;
    used.push_back({name, frames});
    for (int t : threads) bench_config(cfg, frames, t, reps, rows, err);
  }
  set_threads(saved);
  if (!args.flag("--no-torch")) torch_times(used, threads, std::max(1, reps / 2), rows, err);
  if (args.flag("--json")) {
    out << "[\n";
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const Row& r = rows[i];
      out << "  {\"config\": \"" << r.config << "\", \"mode\": \"" << r.mode << "\", \"threads\": " << r.threads
          << ", \"frames\": " << r.frames << ", \"ms_per_frame\": " << r.ms_per_frame << ", \"peak_mb\": " << r.peak_mb;
      if (r.torch_ms_per_frame > 0) out << ", \"torch_ms_per_frame\": " << r.torch_ms_per_frame;
      out << "}" << (i + 1 < rows.size() ? "," : "") << "\n";
    }
    out << "]\n";
    return 0;
  }
  out << "config    mode       threads frames  ms/frame  peak MB  torch ms/frame  torch/ours\n";
  for (const Row& r : rows) {
    char line[256];
    std::snprintf(line, sizeof line, "%-9s %-10s %7d %6d %9.2f %8.1f", r.config.c_str(), r.mode.c_str(), r.threads, r.frames,
                  r.ms_per_frame, r.peak_mb);
    out << line;
    if (r.torch_ms_per_frame > 0) {
      std::snprintf(line, sizeof line, " %15.2f %10.2fx", r.torch_ms_per_frame, r.torch_ms_per_frame / r.ms_per_frame);
      out << line;
    }
    out << "\n";
  }
  return 0;
}

}  // namespace yelan::bench
