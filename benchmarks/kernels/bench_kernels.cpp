#include "benchmarks/kernels/bench_kernels.h"

#include <omp.h>

#include <fstream>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iomanip>
#include <map>
#include <random>
#include <sstream>

#include "benchmarks/kernels/bench_memory.h"
#include "benchmarks/kernels/record.h"
#include "benchmarks/kernels/chart.h"
#include "benchmarks/kernels/onednn_reference.h"
#include "benchmarks/kernels/shapes.h"
#include "benchmarks/kernels/timing.h"
#include "benchmarks/kernels/torch_reference.h"
#include "engine/cli/args.h"
#include "engine/cli/output_path.h"
#include "engine/threads.h"
#include "kernels/conv.h"
#include "kernels/conv_bf16.h"
#include "kernels/peak.h"

namespace yelan::bench {
namespace {

using kernels::Isa;

double measure_peak_gflops(Isa isa, int threads, int reps) {
  const kernels::PeakKernels& k = kernels::peak_kernels(isa);
  const double target_flops = isa == Isa::scalar ? 2e8 : 3e9;  // ~20 ms a call
  const std::int64_t iters = std::int64_t(target_flops / k.flops_per_iteration);
  volatile float sink = 0;
  const double s = median_seconds_per_call(
      [&] {
        float local = 0;
#pragma omp parallel num_threads(threads) reduction(+ : local)
        local += k.fma_loop(iters, 1.f + omp_get_thread_num());
        sink = sink + local;
      },
      reps, 0.05);
  return double(threads) * iters * k.flops_per_iteration / s / 1e9;
}

std::vector<Isa> parse_isas(const std::string& list) {
  std::vector<Isa> out;
  std::stringstream ss(list);
  std::string name;
  while (std::getline(ss, name, ',')) {
    auto isa = kernels::parse_isa(name);
    if (!isa) throw cli::UsageError("--isa-list: unknown ISA '" + name + "'");
    if (!kernels::isa_supported(*isa)) throw cli::UsageError("--isa-list: " + name + " is not supported on this CPU");
    out.push_back(*isa);
  }
  return out;
}

std::vector<int> parse_threads(const std::string& list) {
  std::vector<int> out;
  std::stringstream ss(list);
  std::string item;
  while (std::getline(ss, item, ',')) {
    auto n = parse_thread_count(item);
    if (!n) throw cli::UsageError("--threads-list: '" + item + "' is not a thread count");
    out.push_back(*n);
  }
  return out;
}

std::string json_escape(const std::string& s) {
  std::string o;
  for (char c : s) {
    if (c == '"' || c == '\\') o += '\\';
    o += c;
  }
  return o;
}

void print_json(std::ostream& out, const std::vector<Record>& recs) {
  out << "[\n";
  for (std::size_t i = 0; i < recs.size(); ++i) {
    const Record& r = recs[i];
    out << std::setprecision(6) << "  {\"op\": \"" << r.op << "\", \"where\": \"" << json_escape(r.where)
        << "\", \"kh\": " << r.kh << ", \"kw\": " << r.kw << ", \"stride\": " << r.stride
        << ", \"cin\": " << r.cin << ", \"cout\": " << r.cout << ", \"h\": " << r.h << ", \"w\": " << r.w
        << ", \"algo\": \"" << r.algo << "\", \"isa\": \"" << r.isa << "\", \"threads\": " << r.threads
        << ", \"ms\": " << r.ms << ", \"gflops\": " << r.gflops << ", \"peak_gflops\": " << r.peak_gflops
        << ", \"pct_peak\": " << r.pct_peak;
    if (r.torch_gflops > 0) out << ", \"torch_gflops\": " << r.torch_gflops;
    if (r.onednn_gflops > 0) out << ", \"onednn_gflops\": " << r.onednn_gflops;
    if (r.bytes > 0)
      out << ", \"bytes\": " << r.bytes << ", \"memcpy_ms\": " << r.memcpy_ms << ", \"vs_memcpy\": " << r.ms / r.memcpy_ms;
    out << "}" << (i + 1 < recs.size() ? "," : "") << "\n";
  }
  out << "]\n";
}

}  // namespace

int run_kernels_bench(const std::vector<std::string>& argv, std::ostream& out, std::ostream& err) {
  cli::Args args("bench kernels", argv, {"--isa-list", "--threads-list", "--reps", "--chart", "--only", "--from"},
                 {"--quick", "--json", "--no-torch", "--no-onednn"});
  args.expect_positionals(0, 0);
  const bool quick = args.flag("--quick");
  const int reps = args.int_value_or("--reps", quick ? 3 : 5, 1, 100);
  std::vector<Isa> isas;
  if (auto l = args.value("--isa-list")) isas = parse_isas(*l);
  else if (quick) isas = {kernels::best_isa()};
  else
    for (Isa isa : {Isa::avx2, Isa::avx512, Isa::neon})
      if (kernels::isa_supported(isa)) isas.push_back(isa);
  if (isas.empty()) isas = {Isa::scalar};
  std::vector<int> thread_counts = args.value("--threads-list") ? parse_threads(*args.value("--threads-list"))
                                   : quick ? std::vector<int>{1} : std::vector<int>{1, 2};
  const std::string only = args.value_or("--only", "");

  std::vector<Record> recs;
  std::vector<ConvCase> used;
  if (const auto chart = args.value("--chart")) cli::check_output("--chart", *chart, {args.value_or("--from", "")});
  if (auto from = args.value("--from")) {  // re-render saved results: no measuring
    std::ifstream f(*from);
    if (!f) throw cli::UsageError("--from: cannot read " + *from);
    nlohmann::json j;
    try {
      j = nlohmann::json::parse(f);
    } catch (const nlohmann::json::exception& e) {
      throw cli::UsageError("--from " + *from + ": not a results file (" + e.what() + ")");
    }
    for (const auto& o : j) {
      Record r{o.value("where", ""), o.value("op", ""), o.value("algo", "direct"), o.value("kh", 0), o.value("kw", 0),
               o.value("stride", 0), o.value("cin", 0), o.value("cout", 0), o.value("h", 0), o.value("w", 0),
               o.value("isa", ""), o.value("threads", 0), o.value("ms", 0.0), o.value("gflops", 0.0),
               o.value("peak_gflops", 0.0), o.value("pct_peak", 0.0)};
      r.torch_gflops = o.value("torch_gflops", 0.0);
      r.onednn_gflops = o.value("onednn_gflops", 0.0);
      r.bytes = o.value("bytes", 0.0);
      r.memcpy_ms = o.value("memcpy_ms", 0.0);
      recs.push_back(r);
    }
    if (!args.value("--isa-list")) isas = {kernels::parse_isa(recs.empty() ? "scalar" : recs.back().isa).value_or(kernels::Isa::scalar)};
    if (!args.value("--threads-list")) thread_counts = {1};
  }
  const int saved_threads = threads();
  const Isa saved_isa = kernels::active_isa();
  for (Isa isa : isas) {
    for (int t : thread_counts) {
      if (args.value("--from")) break;
      set_threads(t);
      const double peak_before = measure_peak_gflops(isa, t, reps);
      const std::size_t first = recs.size();
      const kernels::ConvKernels& k = kernels::conv_kernels(isa);
      for (const ConvCase& c : network_conv_cases()) {
        if (quick && !(c.k == 3 && c.stride == 1)) continue;
        if (!only.empty() && c.where.find(only) == std::string::npos) continue;
        if (std::none_of(used.begin(), used.end(), [&](const ConvCase& u) { return u.where == c.where; }))
          used.push_back(c);
        kernels::DeconvShape d;
        d.n = 1; d.ic = c.cin; d.ih = c.h; d.iw = c.w; d.oc = c.cout; d.kh = d.kw = c.k; d.stride = c.stride;
        d.pad_h = d.pad_w = c.pad; d.out_pad_h = c.out_pad_h; d.out_pad_w = c.out_pad_w;
        kernels::ConvShape s;
        if (c.transposed) {
          s = d.as_conv();
        } else {
          s.n = 1; s.ic = c.cin; s.ih = c.h; s.iw = c.w; s.oc = c.cout;
          s.kh = s.kw = c.k; s.stride = c.stride; s.pad_h = s.pad_w = c.pad;
        }
        const std::size_t xn = std::size_t(s.icb()) * s.ih * s.iw * 16;
        const std::size_t yn = std::size_t(s.ocb()) * s.oh() * s.ow() * 16;
        Buffer x(xn, 1), y(yn, 2), w(kernels::conv_weight_floats(s), 3), bias(std::max(s.ocb(), s.icb()) * 16, 4);
        struct Op {
          const char* op;
          std::function<void()> fn;
          const char* algo = "direct";
        };
        std::vector<Op> ops;
        if (c.transposed) {  // deconv input = conv's y, deconv output = conv's x
          ops = {{"deconv2d.fwd", [&] { kernels::deconv_fwd(k, d, y.p, w.p, bias.p, x.p); }},
                 {"deconv2d.bwd_data", [&] { kernels::deconv_bwd_data(k, d, x.p, w.p, y.p); }},
                 {"deconv2d.bwd_weights", [&] { kernels::deconv_bwd_weights(k, d, y.p, x.p, w.p, bias.p); }}};
        } else {
          ops = {{"conv2d.fwd", [&] { k.fwd(s, x.p, w.p, bias.p, y.p); }},
                 {"conv2d.bwd_data", [&] { k.bwd_data(s, y.p, w.p, nullptr, x.p); }},
                 {"conv2d.bwd_weights", [&] { k.bwd_weights(s, x.p, y.p, w.p, bias.p); }}};
        }
        // Winograd's weights are transformed once, outside the timing, as a layer would.
        Buffer wino(kernels::winograd_applicable(s) && !c.transposed ? kernels::winograd_weight_floats(s) : 1, 5);
        if (kernels::winograd_applicable(s) && !c.transposed)
          ops.push_back({"conv2d.fwd", [&] { k.fwd_winograd(s, x.p, wino.p, bias.p, y.p); }, "winograd"});
        // bf16 on AMX tiles (inference; stride 1 and the 2x2/2 up-sampling), on the best ISA's pass.
        const bool amx = kernels::amx_bf16_available() && isa == kernels::best_isa();
        std::vector<std::uint16_t> w16;
        if (amx && !c.transposed && kernels::conv_bf16_applicable(s)) {
          w16.resize(kernels::conv_bf16_weight_halves(s));
          ops.push_back({"conv2d.fwd", [&] { kernels::conv_fwd_bf16_amx(s, x.p, w16.data(), bias.p, y.p); }, "amx-bf16"});
        } else if (amx && c.transposed && kernels::deconv2x2_bf16_applicable(d)) {
          w16.resize(kernels::deconv2x2_bf16_weight_halves(d));
          ops.push_back({"deconv2d.fwd", [&] { kernels::deconv2x2_fwd_bf16_amx(d, y.p, w16.data(), bias.p, x.p); }, "amx-bf16"});
        }
        // Without AMX, on AVX512-BF16 (AMD Zen 4, 5): the Winograd GEMMs and the up-sampling
        // in bf16 pairs, what stage 1 runs there.
        const bool pairs = !amx && kernels::winograd_bf16_enabled() && isa == kernels::best_isa();
        if (pairs && !c.transposed && kernels::winograd_applicable(s)) {
          w16.resize(kernels::winograd_bf16_weight_halves(s));
          ops.push_back({"conv2d.fwd", [&] { kernels::conv_fwd_winograd_bf16(s, x.p, w16.data(), bias.p, y.p); }, "wino-bf16"});
        } else if (pairs && c.transposed && kernels::deconv2x2_bf16_applicable(d)) {
          w16.resize(kernels::deconv2x2_bf16_pairs_weight_halves(d));
          ops.push_back({"deconv2d.fwd", [&] { kernels::deconv2x2_fwd_bf16_pairs(d, y.p, w16.data(), bias.p, x.p); }, "bf16-pairs"});
        }
        for (const auto& op : ops) {
          const double sec = median_seconds_per_call(op.fn, reps, quick ? 0.02 : 0.05);
          Record r{c.where, op.op, op.algo, c.k, c.k, c.stride, c.cin, c.cout, c.h, c.w,
                   kernels::isa_name(isa), t, sec * 1e3, s.flops() / sec / 1e9, peak_before, 0};
          if (!args.flag("--no-onednn") && isa == kernels::best_isa() && r.algo == "direct") {
            const double ms = onednn_ms(c, op.op, reps);  // same thread count, right after ours
            if (ms > 0) r.onednn_gflops = s.flops() / ms / 1e6;
          }
          recs.push_back(r);
          err << "  " << r.where << " " << r.op << " (" << r.algo << "): " << std::setprecision(3) << r.ms << " ms\n";
        }
      }
      if (!quick && (only.empty() || only == "convlstm.step")) bench_convlstm_step(isa, t, reps, recs, err);
      if (!quick && (only.empty() || only == "memory")) bench_memory_bound(isa, t, reps, recs, err);
      // The host is shared: take the better of the peaks measured before and after.
      const double peak = std::max(peak_before, measure_peak_gflops(isa, t, reps));
      err << "peak " << kernels::isa_name(isa) << " x" << t << " thread(s): " << std::fixed << std::setprecision(1)
          << peak << " GFLOP/s\n";
      for (std::size_t i = first; i < recs.size(); ++i) {
        recs[i].peak_gflops = peak;
        recs[i].pct_peak = 100.0 * recs[i].gflops / peak;  // 0 for memory-bound records
      }
    }
  }
  set_threads(saved_threads);
  kernels::set_isa(saved_isa);
  if (!args.flag("--no-torch") && !args.value("--from")) {
    std::string why;
    const TorchTimes torch = torch_conv_times(used, thread_counts, reps, &why);
    if (!why.empty()) err << "no PyTorch comparison: " << why << "\n";
    for (Record& r : recs) {
      auto it = torch.find({r.where, r.op, r.threads});
      if (r.algo == "direct" && it != torch.end() && it->second > 0) r.torch_gflops = r.gflops * r.ms / it->second;
    }
  }
  if (!args.flag("--json")) {
    out << "where                  op                       kernel  cin->cout  HxW     isa   thr        ms   GFLOP/s  %peak"
           "  oneDNN ours/oneDNN  torch ours/torch\n";
    for (const Record& r : recs) {
      char line[256];
      std::snprintf(line, sizeof line, "%-22s %-24s %dx%d/%d %4d->%-4d %3dx%-3d %-6s %d %9.3f %9.1f %6.1f",
                    r.where.c_str(), (r.algo == "direct" ? r.op : r.op + "/" + r.algo).c_str(), r.kh, r.kw, r.stride, r.cin, r.cout, r.h, r.w, r.isa.c_str(),
                    r.threads, r.ms, r.gflops, r.pct_peak);
      out << line;
      if (r.bytes > 0) {
        std::snprintf(line, sizeof line, "  %.2fx memcpy (%.1f GB/s)\n", r.ms / r.memcpy_ms, r.bytes / r.ms / 1e6);
        out << line;
        continue;
      }
      for (double ref : {r.onednn_gflops, r.torch_gflops}) {
        if (ref > 0) std::snprintf(line, sizeof line, "  %6.1f %8.2fx", ref, r.gflops / ref);
        else std::snprintf(line, sizeof line, "  %6s %9s", "-", "-");
        out << line;
      }
      out << "\n";
    }
  }
  if (args.flag("--json")) print_json(out, recs);
  if (auto chart = args.value("--chart")) {
    std::vector<Bar> bars;
    double top = 100;
    for (const Record& r : recs)
      if (r.threads == thread_counts.front() && r.isa == kernels::isa_name(isas.back()) && r.bytes == 0) {
        bars.push_back({r.where + " " + r.op + (r.algo == "direct" ? "" : " (" + r.algo + ")"), r.pct_peak});
        top = std::max(top, std::ceil(r.pct_peak / 50) * 50);
      }
    write_bar_chart_svg(*chart, "% of measured FMA peak (Winograd: direct-equivalent), " +
                                    std::string(kernels::isa_name(isas.back())) + ", " +
                                    std::to_string(thread_counts.front()) + " thread(s)", bars, top);
    err << "chart written to " << *chart << "\n";
  }
  return 0;
}

}  // namespace yelan::bench
