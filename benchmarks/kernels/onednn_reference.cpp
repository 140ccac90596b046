#include "benchmarks/kernels/onednn_reference.h"

#include <algorithm>
#include <unordered_map>
#include <vector>

#include "benchmarks/kernels/timing.h"

#ifdef YELAN_HAVE_ONEDNN
#include <oneapi/dnnl/dnnl.hpp>
#endif

namespace yelan::bench {

#ifdef YELAN_HAVE_ONEDNN
namespace {

using dnnl::memory;
using tag = memory::format_tag;
using dt = memory::data_type;

template <class Pd>
double time_primitive(const Pd& pd, dnnl::primitive prim, const std::vector<std::pair<int, memory::desc>>& args,
                      const dnnl::engine& eng, int reps) {
  std::unordered_map<int, memory> mem;
  for (const auto& [arg, md] : args) {
    memory m(md, eng);
    std::fill_n(static_cast<char*>(m.get_data_handle()), md.get_size(), 0);
    mem.emplace(arg, m);
  }
  dnnl::stream s(eng);
  const double sec = median_seconds_per_call([&] { prim.execute(s, mem); s.wait(); }, reps, 0.05);
  return sec * 1e3;
}

}  // namespace

bool onednn_available() { return true; }

double onednn_ms(const ConvCase& c, const std::string& op, int reps) {
  try {
    dnnl::engine eng(dnnl::engine::kind::cpu, 0);
    const int k = c.k, s = c.stride, p = c.pad;
    // The conv view: for a deconv, its output is the conv's input (see kernels/conv.h).
    const int in_c = c.transposed ? c.cout : c.cin, out_c = c.transposed ? c.cin : c.cout;
    const int ih = c.transposed ? (c.h - 1) * s - 2 * p + k + c.out_pad_h : c.h;
    const int iw = c.transposed ? (c.w - 1) * s - 2 * p + k + c.out_pad_w : c.w;
    const int oh = c.transposed ? c.h : (ih + 2 * p - k) / s + 1;
    const int ow = c.transposed ? c.w : (iw + 2 * p - k) / s + 1;
    const memory::dims strides = {s, s}, pad_l = {p, p};
    // Right padding that makes the window arithmetic land exactly on oh x ow.
    const memory::dims pad_r = {(oh - 1) * s + k - ih - p, (ow - 1) * s + k - iw - p};
    const memory::desc x(memory::dims{1, in_c, ih, iw}, dt::f32, tag::any);
    const memory::desc w(memory::dims{out_c, in_c, k, k}, dt::f32, tag::any);
    const memory::desc y(memory::dims{1, out_c, oh, ow}, dt::f32, tag::any);
    const auto algo = dnnl::algorithm::convolution_direct;
    dnnl::convolution_forward::primitive_desc fwd(
        {dnnl::prop_kind::forward_training, algo, x, w, y, strides, pad_l, pad_r}, eng);
    dnnl::convolution_backward_data::primitive_desc bwd_d({algo, x, w, y, strides, pad_l, pad_r}, eng, fwd);
    dnnl::convolution_backward_weights::primitive_desc bwd_w({algo, x, w, y, strides, pad_l, pad_r}, eng, fwd);
    // deconv forward = conv backward-data, deconv backward-data = conv forward
    const std::string kind = op.substr(op.find('.') + 1);
    const bool as_fwd = (kind == "fwd") != c.transposed;
    if (kind == "bwd_weights")
      return time_primitive(bwd_w, dnnl::convolution_backward_weights(bwd_w),
                            {{DNNL_ARG_SRC, bwd_w.src_desc()}, {DNNL_ARG_DIFF_WEIGHTS, bwd_w.diff_weights_desc()},
                             {DNNL_ARG_DIFF_DST, bwd_w.diff_dst_desc()}}, eng, reps);
    if (as_fwd)
      return time_primitive(fwd, dnnl::convolution_forward(fwd),
                            {{DNNL_ARG_SRC, fwd.src_desc()}, {DNNL_ARG_WEIGHTS, fwd.weights_desc()},
                             {DNNL_ARG_DST, fwd.dst_desc()}}, eng, reps);
    return time_primitive(bwd_d, dnnl::convolution_backward_data(bwd_d),
                          {{DNNL_ARG_DIFF_SRC, bwd_d.diff_src_desc()}, {DNNL_ARG_WEIGHTS, bwd_d.weights_desc()},
                           {DNNL_ARG_DIFF_DST, bwd_d.diff_dst_desc()}}, eng, reps);
  } catch (const dnnl::error&) {
    return -1;
  }
}
#else
bool onednn_available() { return false; }
double onednn_ms(const ConvCase&, const std::string&, int) { return -1; }
#endif

}  // namespace yelan::bench
