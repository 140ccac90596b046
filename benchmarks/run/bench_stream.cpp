#include "benchmarks/run/bench_stream.h"

#include <charconv>
#include <cmath>

#include <cstdio>
#include <sstream>

#include "benchmarks/run/xy_chart.h"
#include "camera/sim/presets.h"
#include "engine/cli/args.h"
#include "engine/cli/output_path.h"
#include "engine/run/stream_eval.h"
#include "engine/threads.h"
#include "engine/train/evaluate.h"

namespace yelan::bench {

namespace {

struct Sweep {
  const char* name;      // "beta" or "rate"
  const char* command;   // for messages
  std::string defaults;  // the values swept
};

// The mask IoU's chart beside the accuracy's: F.svg -> F-iou.svg.
std::string iou_chart_path(const std::string& chart) {
  const std::size_t dot = chart.size() >= 4 && chart.compare(chart.size() - 4, 4, ".svg") == 0 ? chart.size() - 4 : chart.size();
  return chart.substr(0, dot) + "-iou.svg";
}

int sweep(const Sweep& what, const std::vector<std::string>& argv, std::ostream& out, std::ostream& err) {
  cli::Args a(what.command, argv,
              {"--weights", "--values", "--scenes", "--seed", "--seconds", "--rate", "--beta", "--mask-max-age", "--threads", "--chart"},
              {"--json"});
  a.expect_positionals(0, 0);
  const auto w = a.value("--weights");
  if (!w) throw cli::UsageError(std::string(what.command) + " needs --weights W");
  if (const auto chart = a.value("--chart")) {
    cli::check_output("--chart", *chart, {*w});
    if (std::string(what.name) != "rate") cli::check_output("--chart", iou_chart_path(*chart), {*w});
  }
  std::vector<double> values;
  for (const auto& v : cli::split_list(a.value_or("--values", what.defaults))) {
    double d = 0;
    const auto [ptr, ec] = std::from_chars(v.data(), v.data() + v.size(), d);
    if (ec != std::errc() || ptr != v.data() + v.size() || !std::isfinite(d) || d < 0 || d > 1e6)
      throw cli::UsageError("--values: '" + v + "' is not a number in [0, 1e6]");
    values.push_back(d);
  }
  const int scenes = a.int_value_or("--scenes", 12, 1, 1 << 20);
  const std::uint64_t seed = std::uint64_t(a.int_value_or("--seed", 1, 0, 1 << 30));
  const double seconds = a.number_or("--seconds", 1, 0, 3600, true);
  set_threads(a.int_value_or("--threads", 1, 1, 1024));
  std::vector<camera::sim::SimSpec> specs;
  for (const auto& n : train::draw_test_scenes(seed, scenes)) specs.push_back(camera::sim::preset_spec(n));
  err << what.command << ": simulating " << scenes << " test scenes (seed " << seed << ")\n";
  const auto sims = run::simulate_scenes(specs, seed, seconds, 0.1, err);
  struct Row {
    double value;
    run::StreamEvalResult r;
  };
  std::vector<Row> rows;
  for (double v : values) {
    run::RunOptions o;
    o.rate_hz = a.number_or("--rate", 50, 0, 10000, true);
    o.beta = a.number_or("--beta", 0.99, 0, 2);
    if (a.value("--mask-max-age")) o.mask_max_age = a.int_value_or("--mask-max-age", 0, 0, 1000);  // else the model's
    const std::string name = what.name;
    if (name == "crop_margin") o.crop_margin = int(v);
    else (name == "beta" ? o.beta : o.rate_hz) = v;
    rows.push_back({v, run::evaluate_stream(*w, sims, o)});
    const auto& r = rows.back().r;
    err << "  " << what.name << " " << v << ": MPJPE " << r.paper.mpjpe_mm << " mm, stage 1 on " << 100 * r.mask_run_fraction
        << "% of ticks, " << r.ms_per_tick << " ms per tick\n";
  }
  // The reference for "time saved": the most expensive setting of the sweep.
  double ref_ms = 0;
  for (const auto& row : rows) ref_ms = std::max(ref_ms, row.r.ms_per_tick);
  if (a.flag("--json")) {
    out << "[\n";
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const auto& r = rows[i].r;
      out << "  {\"" << what.name << "\": " << rows[i].value << ", \"mpjpe_mm\": " << r.paper.mpjpe_mm
          << ", \"pck150\": " << r.paper.pck150 << ", \"auc\": " << r.paper.auc << ", \"mpjpe_root_mm\": " << r.paper.mpjpe_root_mm
          << ", \"mpjpe_depth_prior_mm\": " << r.deployed.mpjpe_mm << ", \"mask_run_fraction\": " << r.mask_run_fraction
          << ", \"ms_per_tick\": " << r.ms_per_tick << ", \"tore_ms\": " << r.tore_ms << ", \"stage1_ms\": " << r.stage1_ms
          << ", \"stage2_ms\": " << r.stage2_ms << ", \"crop_share\": " << r.crop_share << ", \"time_vs_slowest\": " << r.ms_per_tick / ref_ms
          << ", \"mask_iou\": ";
      if (r.mask_iou >= 0) out << r.mask_iou;
      else out << "null";
      out << ", \"ticks\": " << r.ticks << ", \"stale\": " << r.stale << ", \"poses_scored\": " << r.poses_scored
          << ", \"scenes\": " << scenes << ", \"threads\": " << threads() << "}" << (i + 1 < rows.size() ? "," : "") << "\n";
    }
    out << "]\n";
  } else {
    out << what.name
        << "      MPJPE mm  (depth prior)  PCK@150  mask IoU  stage 1 ran  ms/tick  stage1 ms  stage2 ms  head on  time vs slowest\n";
    for (const auto& row : rows) {
      const auto& r = row.r;
      char line[256];
      char iou[16] = "        -";  // not measured: no dancer scene, or no mask net
      if (r.mask_iou >= 0) std::snprintf(iou, sizeof iou, "%9.3f", r.mask_iou);
      std::snprintf(line, sizeof line, "%-8g %9.1f %14.1f %8.3f %s %11.0f%% %8.2f %10.2f %10.2f %7.0f%% %15.2f\n", row.value,
                    r.paper.mpjpe_mm, r.deployed.mpjpe_mm, r.paper.pck150, iou, 100 * r.mask_run_fraction, r.ms_per_tick,
                    r.stage1_ms, r.stage2_ms, 100 * r.crop_share, r.ms_per_tick / ref_ms);
      out << line;
    }
  }
  if (const auto chart = a.value("--chart")) {
    XySeries paper{"paper protocol (true head depth)", "#2471a3", {}}, prior{"depth from the body-height prior", "#c0392b", {}};
    const bool by_beta = std::string(what.name) != "rate";  // time on x: beta and crop margin
    for (const auto& row : rows) {
      std::ostringstream label;
      label << what.name << " " << row.value;
      const double x = by_beta ? row.r.ms_per_tick : row.value;
      paper.points.push_back({x, row.r.paper.mpjpe_mm, by_beta ? label.str() : ""});
      prior.points.push_back({x, row.r.deployed.mpjpe_mm, ""});
    }
    std::ostringstream title;
    title << (std::string(what.name) == "beta"          ? "Early exit: accuracy against time per pose"
              : std::string(what.name) == "crop_margin" ? "Stage 2 cropped to the mask's box: accuracy against time per pose"
                                                        : "Accuracy against pose rate (trained at 50/s)")
          << ", "
          << scenes << " test scenes, " << threads() << " thread" << (threads() > 1 ? "s" : "");
    const std::string png = write_xy_chart(*chart, title.str(), by_beta ? "ms per pose (mean over ticks)" : "poses per second",
                                           "MPJPE (mm)", {paper, prior});
    err << "wrote " << *chart << (png.empty() ? "" : " and " + png) << "\n";
    // The masks stage 2 read, beside the poses: early exit and the crop trade them for time.
    if (by_beta && !rows.empty() && rows.front().r.mask_iou >= 0) {
      XySeries iou{"mask stage 2 read against the true mask", "#1e8449", {}};
      for (const auto& row : rows) {
        std::ostringstream label;
        label << what.name << " " << row.value;
        iou.points.push_back({row.r.ms_per_tick, row.r.mask_iou, label.str()});
      }
      const std::string iou_chart = iou_chart_path(*chart);
      const std::string iou_png = write_xy_chart(iou_chart, "Mask IoU as deployed against time per pose, " + std::to_string(scenes) +
                                                                " test scenes", "ms per pose (mean over ticks)", "mask IoU", {iou});
      err << "wrote " << iou_chart << (iou_png.empty() ? "" : " and " + iou_png) << "\n";
    }
  }
  return 0;
}

}  // namespace

int run_early_exit_bench(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  return sweep({"beta", "bench early-exit", "0.5,0.7,0.8,0.9,0.95,0.99,1.01"}, args, out, err);
}

int run_crop_bench(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  return sweep({"crop_margin", "bench crop", "0,4,8,16,32"}, args, out, err);
}

int run_rate_sweep_bench(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  return sweep({"rate", "bench rate-sweep", "20,50,100,150,200"}, args, out, err);
}

}  // namespace yelan::bench
