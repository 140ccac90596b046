#include "benchmarks/kernels/bench_memory.h"

#include <omp.h>

#include <cstring>
#include <functional>
#include <iomanip>

#include "benchmarks/kernels/timing.h"
#include "kernels/bn.h"
#include "kernels/conv.h"
#include "kernels/heatmap.h"
#include "kernels/lstm.h"
#include "kernels/pool.h"

namespace yelan::bench {
namespace {

using kernels::Isa;

// A parallel memcpy of `bytes` (it reads and writes them: 2 x bytes of traffic).
double memcpy_ms(std::size_t bytes, int threads, int reps) {
  Buffer a(bytes / 4 + 16, 1), b(bytes / 4 + 16, 2);
  return 1e3 * median_seconds_per_call(
                   [&] {
#pragma omp parallel num_threads(threads)
                     {
                       const std::size_t per = (bytes / threads + 63) / 64 * 64;
                       const std::size_t begin = std::min(bytes, per * omp_get_thread_num());
                       const std::size_t end = std::min(bytes, begin + per);
                       std::memcpy(reinterpret_cast<char*>(b.p) + begin, reinterpret_cast<char*>(a.p) + begin,
                                   end - begin);
                     }
                   },
                   reps, 0.03);
}

struct Case {
  std::string where, op;
  int c, h, w, k, stride;
  double bytes;  // minimal traffic: every input read once, every output written once
  std::function<void()> fn;
};

void run(const std::vector<Case>& cases, Isa isa, int threads, int reps, std::vector<Record>& out,
         std::ostream& err) {
  for (const Case& c : cases) {
    Record r{c.where, c.op, "simd", c.k, c.k, c.stride, c.c, c.c, c.h, c.w, kernels::isa_name(isa), threads, 0, 0, 0, 0};
    r.ms = 1e3 * median_seconds_per_call(c.fn, reps, 0.03);
    r.bytes = c.bytes;
    r.memcpy_ms = memcpy_ms(std::size_t(c.bytes / 2), threads, reps);
    out.push_back(r);
    err << "  " << r.where << " " << r.op << ": " << std::setprecision(3) << r.ms << " ms, " << r.ms / r.memcpy_ms
        << "x memcpy\n";
  }
}

}  // namespace

void bench_memory_bound(Isa isa, int threads, int reps, std::vector<Record>& out, std::ostream& err) {
  // BN+ReLU and max pooling on the ResNet conv1 output (64 x 130 x 173).
  const kernels::BnShape bs{1, 4, 130 * 173};
  const std::size_t N = std::size_t(bs.cb) * bs.pixels * 16;
  Buffer x(N, 1), y(N, 2), dy(N, 3), dx(N, 4), ch(4 * 64, 5);
  std::vector<float> gamma(64, 1.f), var(64, 1.f);
  const kernels::BnKernels& bn = kernels::bn_kernels(isa);
  const kernels::PoolShape ps{4, 130, 173, 3, 2, 1};
  const std::size_t NO = std::size_t(4) * ps.oh() * ps.ow() * 16;
  Buffer py(NO, 6);
  std::vector<std::int32_t> arg(NO, 0);
  const kernels::PoolKernels& pool = kernels::pool_kernels(isa);
  // ConvLSTM point-wise update, hidden 128 at 33 x 44; softmax of 13 joint maps at 33 x 44.
  const kernels::LstmShape ls{1, 8, 33 * 44};
  const std::size_t E = std::size_t(ls.hb) * ls.pixels * 16;
  Buffer gates(4 * E, 7), act(4 * E, 8), c0(E, 9), c1(E, 10), h(E, 11), t(E, 12), dh(E, 13), dg(4 * E, 14);
  const kernels::LstmKernels& lstm = kernels::lstm_kernels(isa);
  const kernels::HeatmapKernels& hm = kernels::heatmap_kernels(isa);
  const std::size_t HP = 33 * 44;
  const double f = 4;  // bytes per float
  std::vector<Case> cases = {
      {"resnet.bn1", "bn_relu.fwd", 64, 130, 173, 1, 1, f * 2 * N,
       [&] { bn.fwd(bs, x.p, ch.p, var.data(), gamma.data(), ch.p, 1e-5f, true, y.p); }},
      {"resnet.bn1", "bn.stats", 64, 130, 173, 1, 1, f * N, [&] { bn.stats(bs, x.p, ch.p, ch.p + 64); }},
      {"resnet.bn1", "bn_relu.bwd", 64, 130, 173, 1, 1, f * 4 * N,
       [&] { bn.bwd(bs, x.p, y.p, dy.p, ch.p, var.data(), gamma.data(), 1e-5f, true, dx.p, ch.p + 64, ch.p + 128); }},
      {"resnet.maxpool", "maxpool.fwd", 64, 130, 173, 3, 2, f * (N + 2 * NO),
       [&] { pool.max_fwd(ps, x.p, py.p, arg.data()); }},
      {"resnet.maxpool", "maxpool.bwd", 64, 130, 173, 3, 2, f * (2 * NO + N),
       [&] { pool.max_bwd(ps, py.p, arg.data(), dx.p); }},
      {"convlstm.cell", "lstm.fwd", 128, 33, 44, 1, 1, f * 12 * E,
       [&] { lstm.fwd(ls, gates.p, c0.p, act.p, c1.p, h.p, t.p); }},
      {"convlstm.cell", "lstm.bwd", 128, 33, 44, 1, 1, f * 13 * E,
       [&] { lstm.bwd(ls, act.p, c0.p, t.p, dh.p, c1.p, dg.p, c0.p); }},
      {"heatmap.softmax", "softmax.fwd", 13, 33, 44, 1, 1, f * 2 * HP * 16,
       [&] { hm.softmax_fwd(1, HP, x.p, y.p); }},
  };
  run(cases, isa, threads, reps, out, err);
}

void bench_convlstm_step(Isa isa, int threads, int reps, std::vector<Record>& out, std::ostream& err) {
  kernels::ConvShape s;  // gates = conv(cat[x, h]): 128 + 128 -> 4 x 128, 3x3, 33 x 44
  s.ic = 256; s.ih = 33; s.iw = 44; s.oc = 512; s.kh = s.kw = 3; s.pad_h = s.pad_w = 1;
  const kernels::LstmShape ls{1, 8, 33 * 44};
  const std::size_t E = std::size_t(ls.hb) * ls.pixels * 16;
  Buffer xh(std::size_t(s.icb()) * 33 * 44 * 16, 1), w(kernels::conv_weight_floats(s), 2), b(512, 3);
  Buffer gates(4 * E, 4), act(4 * E, 5), c0(E, 6), c1(E, 7), h(E, 8), t(E, 9), dg(4 * E, 10), dxh(std::size_t(s.icb()) * 33 * 44 * 16, 11);
  const kernels::ConvKernels& conv = kernels::conv_kernels(isa);
  const kernels::LstmKernels& lstm = kernels::lstm_kernels(isa);
  const struct {
    const char* op;
    double flops;
    std::function<void()> fn;
  } ops[] = {
      {"convlstm.step.fwd", s.flops(), [&] {
         conv.fwd(s, xh.p, w.p, b.p, gates.p);
         lstm.fwd(ls, gates.p, c0.p, act.p, c1.p, h.p, t.p);
       }},
      {"convlstm.step.bwd", 2 * s.flops(), [&] {
         lstm.bwd(ls, act.p, c0.p, t.p, h.p, c1.p, dg.p, c0.p);
         conv.bwd_data(s, dg.p, w.p, nullptr, dxh.p);
         conv.bwd_weights(s, xh.p, dg.p, w.p, b.p);
       }},
  };
  for (const auto& op : ops) {
    Record r{"convlstm.step", op.op, "direct", 3, 3, 1, 256, 512, 33, 44, kernels::isa_name(isa), threads, 0, 0, 0, 0};
    const double sec = median_seconds_per_call(op.fn, reps, 0.05);
    r.ms = sec * 1e3;
    r.gflops = op.flops / sec / 1e9;
    out.push_back(r);
    err << "  convlstm.step " << op.op << ": " << std::setprecision(3) << r.ms << " ms\n";
  }
}

}  // namespace yelan::bench
