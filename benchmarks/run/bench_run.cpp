#include "benchmarks/run/bench_run.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <numeric>
#include <sstream>
#include <unistd.h>

#include "camera/sim/presets.h"
#include "benchmarks/bench_util.h"
#include "engine/cli/args.h"
#include "engine/mask_net.h"
#include "engine/pose_net.h"
#include "engine/run/pipeline.h"
#include "engine/subprocess.h"
#include "engine/threads.h"
#include "weights_tools/network_io.h"

namespace yelan::bench {
namespace {

struct Collect final : camera::sim::SimSink {
  std::vector<camera::Event> ev;
  void events(std::span<const camera::Event> e) override { ev.insert(ev.end(), e.begin(), e.end()); }
};

std::string random_weights(const std::string& config, const std::string& dir) {
  const ModelConfig cfg = load_model_config(config);
  MaskNet mask(cfg);
  PoseNet pose(cfg);
  mask.init(11);
  pose.init(12);
  layers::ParamList mp, pp;
  mask.params(mp);
  pose.params(pp);
  weights::randomise_batchnorm(mp, 13);
  weights::randomise_batchnorm(pp, 14);
  const weights::Weights w = weights::weights_of(cfg, mp, pp);
  const std::string path = (std::filesystem::path(dir) / (cfg.name + ".h5")).string();
  weights::save_weights(path, w);
  return path;
}

}  // namespace

int run_pipeline_bench(const std::vector<std::string>& argv, std::ostream& out, std::ostream& err) {
  cli::Args args("bench run", argv, {"--configs", "--threads-list", "--rate", "--seconds", "--beta", "--weights", "--crop-margin", "--bf16", "--pose-bf16", "--mask-max-age"}, {"--json", "--no-torch", "--whole-tore"});
  args.expect_positionals(0, 0);
  const double rate = args.number_or("--rate", 50, 0, 10000, true), seconds = args.number_or("--seconds", 2, 0, 3600, true);
  // Absent: each model's own run.beta (its shipped setting; 0.99, the paper's, without one).
  const double beta = args.value("--beta") ? args.number_or("--beta", 0.99, 0, 2) : -1;
  const int crop_margin = args.value("--crop-margin") ? args.int_value_or("--crop-margin", 0, 0, 4096) : -1;
  const std::vector<int> threads = threads_list(args);
  // The events: a dancer simulated in memory.
  camera::sim::SimSpec spec = camera::sim::preset_spec("ben-dance5-front-medium-static");
  spec.duration_s = seconds;
  camera::sim::Simulator sim(spec);
  Collect c;
  sim.run_until(seconds, c);
  err << "  " << c.ev.size() << " simulated events over " << seconds << " s\n";
  const std::string dir = (std::filesystem::temp_directory_path() / ("yelan-bench-run-" + std::to_string(::getpid()))).string();
  std::filesystem::create_directories(dir);
  std::vector<std::pair<std::string, std::string>> models;  // config, weights
  if (const auto w = args.value("--weights"))
    for (const auto& f : cli::split_list(*w)) models.push_back({"", f});
  else
    for (const auto& cfg : cli::split_list(args.value_or("--configs", "small,paper"))) models.push_back({cfg, random_weights(cfg, dir)});
  struct Row {
    std::string config, weights;
    int threads;
    double poses_per_s, p50, p99, tore50, s1_50, s2_50, mask_frac;
    double nets_ms = 0;                    // mean per tick of stage 1 + stage 2 (the networks' work)
    double torch_ms = -1;                  // the same work in PyTorch (benchmarks/torch/pipeline_bench.py)
    double crop_share = 1;                 // mean share of the frame stage 2's head ran on
  };
  std::vector<Row> rows;
  const int saved = yelan::threads();
  for (const auto& [cfg, wpath] : models)
    for (int t : threads) {
      set_threads(t);
      run::RunOptions o;
      o.rate_hz = rate;
      o.beta = beta;
      o.crop_margin = crop_margin;
      o.tore_box = !args.flag("--whole-tore");
      if (args.value("--bf16")) o.bf16 = args.on_off("--bf16");
      if (args.value("--pose-bf16")) o.pose_bf16 = args.on_off("--pose-bf16");
      if (args.value("--mask-max-age")) o.mask_max_age = args.int_value_or("--mask-max-age", 0, 0, 1000);
      run::PosePipeline pipe(wpath, 346, 260, o);
      std::uint64_t n = 0;
      const auto t0 = std::chrono::steady_clock::now();
      pipe.push(c.ev, [&](const run::Pose&) { ++n; });
      pipe.finish(c.ev.empty() ? 0 : c.ev.back().t, [&](const run::Pose&) { ++n; });
      const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
      const auto& s = pipe.stats();
      rows.push_back({pipe.config_name(), wpath, t, double(n) / wall, run::percentile(s.times.tick_ms, 0.5), run::percentile(s.times.tick_ms, 0.99),
                      run::percentile(s.times.tore_ms, 0.5), run::percentile(s.times.stage1_ms, 0.5), run::percentile(s.times.stage2_ms, 0.5),
                      double(s.mask_runs) / double(std::max<std::uint64_t>(1, s.ticks - s.stale))});
      double nets = 0;
      for (std::size_t i = 0; i < s.times.stage1_ms.size(); ++i) nets += s.times.stage1_ms[i] + s.times.stage2_ms[i];
      rows.back().nets_ms = nets / double(std::max<std::size_t>(1, s.times.stage1_ms.size()));
      rows.back().crop_share = run::crop_share(s);
      err << "  " << pipe.config_name() << " x" << t << ": " << double(n) / wall << " poses/s (stage 1 " << pipe.stage1_precision() << (pipe.stage2_bf16() ? ", stage 2 bf16 on AMX" : "") << ", age cap " << pipe.mask_max_age() << "; beta " << pipe.beta()
          << "; TORE read in stage 2's box on " << s.tore_box_ticks << " of " << s.ticks << " ticks, "
          << 100 * s.tore_box_area / double(std::max<std::uint64_t>(1, s.tore_box_ticks)) << "% of the frame; TORE mean "
          << std::accumulate(s.times.tore_ms.begin(), s.times.tore_ms.end(), 0.0) / double(std::max<std::size_t>(1, s.times.tore_ms.size())) << " ms)\n";
    }
  set_threads(saved);
  // PyTorch after ours, never both thread pools at once.
  if (!args.flag("--no-torch")) {
    if (!reference_python_imports("torch")) {
      err << "no PyTorch comparison: /usr/bin/python3 cannot import torch\n";
    } else {
      for (Row& r : rows) {
        Program py({"/usr/bin/python3", YELAN_SOURCE_DIR "/benchmarks/torch/pipeline_bench.py", "--weights", r.weights,
                    "--threads", std::to_string(r.threads), "--mask-fraction", std::to_string(r.mask_frac)});
        py.capture_stdout = true;
        const ProgramResult res = run_program(py);
        if (!res.ok()) err << "  PyTorch " << r.config << " x" << r.threads << " failed: " << res.why() << "\n";
        std::istringstream lines(res.out);
        for (std::string line; std::getline(lines, line);) std::sscanf(line.c_str(), "ms_per_tick %lf", &r.torch_ms);
        err << "  PyTorch " << r.config << " x" << r.threads << ": " << r.torch_ms << " ms per tick of network work\n";
      }
    }
  }
  std::filesystem::remove_all(dir);
  if (args.flag("--json")) {
    out << "[\n";
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const Row& r = rows[i];
      out << "  {\"config\": \"" << r.config << "\", \"weights\": \"" << r.weights << "\", \"threads\": " << r.threads << ", \"poses_per_s\": " << r.poses_per_s
          << ", \"p50_ms\": " << r.p50 << ", \"p99_ms\": " << r.p99 << ", \"tore_p50_ms\": " << r.tore50
          << ", \"stage1_p50_ms\": " << r.s1_50 << ", \"stage2_p50_ms\": " << r.s2_50
          << ", \"mask_run_fraction\": " << r.mask_frac << ", \"rate\": " << rate << ", \"nets_ms_per_tick\": " << r.nets_ms
          << ", \"crop_share\": " << r.crop_share;
      if (r.torch_ms > 0) out << ", \"torch_nets_ms_per_tick\": " << r.torch_ms << ", \"ours_vs_torch\": " << r.torch_ms / r.nets_ms;
      out << "}" << (i + 1 < rows.size() ? "," : "") << "\n";
    }
    out << "]\n";
    return 0;
  }
  out << "config   threads  poses/s  tick p50 ms  p99 ms  TORE p50  stage1 p50  stage2 p50  stage 1 ran  nets ms/tick  PyTorch  ours/PyTorch\n";
  for (const Row& r : rows) {
    char line[320];
    std::snprintf(line, sizeof line, "%-8s %7d %8.1f %12.2f %7.2f %9.2f %11.2f %11.2f %10.0f%% %13.2f %8.2f %12.2fx\n",
                  r.config.c_str(), r.threads, r.poses_per_s, r.p50, r.p99, r.tore50, r.s1_50, r.s2_50, 100 * r.mask_frac,
                  r.nets_ms, r.torch_ms, r.torch_ms > 0 ? r.torch_ms / r.nets_ms : 0.0);
    out << line;
  }
  return 0;
}

}  // namespace yelan::bench
