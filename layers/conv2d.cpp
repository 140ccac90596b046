#include "layers/conv2d.h"

#include <algorithm>
#include <stdexcept>
#include <string>

#include "kernels/conv_bf16.h"

namespace yelan::layers {

namespace {
std::vector<std::int64_t> weight_shape(const ConvSpec& s) {
  return s.transposed ? std::vector<std::int64_t>{s.in, s.out, s.k, s.k} : std::vector<std::int64_t>{s.out, s.in, s.k, s.k};
}
}  // namespace

std::uint64_t& conv_flops() {
  static std::uint64_t count = 0;
  return count;
}

bool& winograd_allowed() {
  static bool allowed = true;
  return allowed;
}

bool& bf16_convs() {
  static thread_local bool on = false;  // a pipeline's precision, not its neighbour's on another thread
  return on;
}

Bf16Path bf16_path_if(bool on) {
  if (!on) return Bf16Path::none;
  if (kernels::amx_bf16_enabled()) return Bf16Path::amx;
  return kernels::winograd_bf16_enabled() ? Bf16Path::winograd : Bf16Path::none;
}

Bf16Path bf16_path() { return bf16_path_if(bf16_convs()); }

const char* bf16_path_name(Bf16Path p) {
  switch (p) {
    case Bf16Path::amx: return "bf16 on AMX";
    case Bf16Path::winograd: return "bf16 Winograd on AVX512-BF16";
    case Bf16Path::none: break;
  }
  return "fp32";
}

bool bf16_active() { return bf16_path() != Bf16Path::none; }

// A 1x1 convolution is a copy into bf16 and a pass over the result as much as a product
// (stage 1's 24->16 output layer: 0.25 against 0.15 ms in fp32), so it stays fp32.
bool takes_bf16(const kernels::ConvShape& s) {
  return bf16_path() == Bf16Path::amx && s.kh * s.kw > 1 && kernels::conv_bf16_applicable(s);
}

Bf16Path up_bf16_path(const kernels::DeconvShape& d) {
  return kernels::deconv2x2_bf16_applicable(d) ? bf16_path() : Bf16Path::none;
}

std::vector<ConvRecord>*& conv_trace() {
  static std::vector<ConvRecord>* trace = nullptr;
  return trace;
}

Conv2d::Conv2d(const ConvSpec& spec) : weight("weight", weight_shape(spec)), spec_(spec) {
  if (spec.bias) bias = std::make_unique<Param>("bias", std::vector<std::int64_t>{spec.out});
}

void Conv2d::params(const std::string& prefix, ParamList& out) {
  out.push_back({prefix + "weight", &weight});
  if (bias) out.push_back({prefix + "bias", bias.get()});
}

void Conv2d::init(std::uint64_t seed) {
  // PyTorch computes fan_in from weight.size(1) * k * k: for ConvTranspose that is `out`.
  const std::int64_t fan_in = std::int64_t(weight.shape[1]) * spec_.k * spec_.k;
  init_uniform_fan_in(weight, fan_in, seed);
  if (bias) init_uniform_fan_in(*bias, fan_in, seed ^ 0x9e3779b97f4a7c15ull);
  weights_changed();
}

kernels::DeconvShape Conv2d::deconv_shape(const Act& x) const {
  kernels::DeconvShape d;
  d.n = x.n; d.ic = spec_.in; d.ih = x.h; d.iw = x.w; d.oc = spec_.out; d.kh = d.kw = spec_.k;
  d.stride = spec_.stride; d.pad_h = d.pad_w = spec_.pad; d.out_pad_h = spec_.out_pad_h; d.out_pad_w = spec_.out_pad_w;
  return d;
}

kernels::ConvShape Conv2d::conv_shape(const Act& x) const {
  if (spec_.transposed) return deconv_shape(x).as_conv();
  kernels::ConvShape s;
  s.n = x.n; s.ic = spec_.in; s.ih = x.h; s.iw = x.w; s.oc = spec_.out; s.kh = s.kw = spec_.k;
  s.stride = spec_.stride; s.pad_h = s.pad_w = spec_.pad;
  return s;
}

Act Conv2d::out_shape(const Act& x) const {
  if (spec_.transposed) {
    const auto d = deconv_shape(x);
    return {nullptr, x.n, spec_.out, d.oh(), d.ow()};
  }
  const auto s = conv_shape(x);
  return {nullptr, x.n, spec_.out, s.oh(), s.ow()};
}

void Conv2d::pack(const kernels::ConvShape& s) {
  if (packed_) return;
  const std::size_t n = kernels::conv_weight_floats(s);
  if (fwd_.size() != n) {
    fwd_ = Floats(n);
    bwd_ = Floats(n);
    dw_packed_ = Floats(n);
  }
  kernels::pack_conv_weights(s, weight.value.data(), kernels::ConvPack::fwd, fwd_.data());
  kernels::pack_conv_weights(s, weight.value.data(), kernels::ConvPack::bwd_data, bwd_.data());
  up_bf16_.clear();
  if (kernels::winograd_applicable(s) && !spec_.transposed) {
    wino_ = Floats(kernels::winograd_weight_floats(s));
    kernels::pack_winograd_weights(s, weight.value.data(), wino_.data());
  }
  const int blocks16 = ((spec_.out + 15) / 16) * 16;
  bias16_ = Floats(blocks16);
  db16_ = Floats(std::max(s.icb(), s.ocb()) * 16);
  if (bias)
    for (int o = 0; o < spec_.out; ++o) bias16_[o] = bias->value[o];
  packed_ = true;
}

static void check(const Act& a, int c, int h, int w, const char* what) {
  if (a.c != c || a.h != h || a.w != w)
    throw std::invalid_argument(std::string("conv: ") + what + " is " + std::to_string(a.c) + "x" + std::to_string(a.h) +
                                "x" + std::to_string(a.w) + ", expected " + std::to_string(c) + "x" +
                                std::to_string(h) + "x" + std::to_string(w));
}

void Conv2d::record(const Act& x, const Act& y, const kernels::ConvShape& s) const {
  conv_flops() += std::uint64_t(s.flops());
  if (conv_trace())
    conv_trace()->push_back({&weight, spec_.k, spec_.stride, spec_.transposed, x.c, x.h, x.w, y.c, y.h, y.w,
                             std::uint64_t(s.flops()) / std::uint64_t(std::max(1, x.n))});
}

void Conv2d::run_forward(const Act& x, const Act& y, const float* w, const float* wino, const float* b,
                         bool winograd, bool relu) {
  if (relu && spec_.transposed) throw std::logic_error("conv: a fused ReLU is for forward convolutions");
  auto s = conv_shape(x);
  s.relu = relu;
  record(x, y, s);
  const kernels::ConvKernels& k = kernels::conv_kernels();
  if (spec_.transposed)
    kernels::deconv_fwd(k, deconv_shape(x), x.data, w, b, y.data);
  else if (winograd && wino && winograd_allowed() && kernels::winograd_pays(s))
    k.fwd_winograd(s, x.data, wino, b, y.data);
  else
    k.fwd(s, x.data, w, b, y.data);
}

void Conv2d::check_io(const Act& x, const Act& y) const {
  const Act o = out_shape(x);
  check(x, spec_.in, x.h, x.w, "input");
  check(y, o.c, o.h, o.w, "output");
  if (!conv_shape(x).valid())
    throw std::invalid_argument("conv: input " + std::to_string(x.h) + "x" + std::to_string(x.w) + " too small");
}

void Conv2d::forward(const Act& x, const Act& y, bool winograd) {
  check_io(x, y);
  pack(conv_shape(x));
  const Bf16Path up = spec_.transposed && !grad_enabled() ? up_bf16_path(deconv_shape(x)) : Bf16Path::none;
  if (up != Bf16Path::none) {
    const kernels::DeconvShape d = deconv_shape(x);
    const bool amx = up == Bf16Path::amx;
    if (up_bf16_.empty() || up_bf16_layout_ != up) {
      up_bf16_.resize(amx ? kernels::deconv2x2_bf16_weight_halves(d) : kernels::deconv2x2_bf16_pairs_weight_halves(d));
      (amx ? kernels::pack_deconv2x2_bf16_weights : kernels::pack_deconv2x2_bf16_pairs_weights)(
          d, weight.value.data(), up_bf16_.data());
      up_bf16_layout_ = up;
    }
    record(x, y, conv_shape(x));
    (amx ? kernels::deconv2x2_fwd_bf16_amx : kernels::deconv2x2_fwd_bf16_pairs)(
        d, x.data, up_bf16_.data(), bias ? bias16_.data() : nullptr, y.data);
    return;
  }
  run_forward(x, y, spec_.transposed ? bwd_.data() : fwd_.data(), wino_.size() ? wino_.data() : nullptr,
              bias ? bias16_.data() : nullptr, winograd);
}

void Conv2d::pack_folded(const kernels::ConvShape& s, const float* scale, const float* shift) {
  if (folded_) return;
  // Output channel o is dim 0 of OIHW and dim 1 of a transposed conv's IOHW.
  Floats w(weight.numel());
  const std::size_t kk = std::size_t(spec_.k) * spec_.k;
  for (std::size_t i = 0; i < weight.numel(); ++i) {
    const std::size_t o = spec_.transposed ? (i / kk) % spec_.out : i / (kk * spec_.in);
    w[i] = weight.value[i] * scale[o];
  }
  fold_w_ = Floats(kernels::conv_weight_floats(s));
  kernels::pack_conv_weights(s, w.data(), spec_.transposed ? kernels::ConvPack::bwd_data : kernels::ConvPack::fwd,
                             fold_w_.data());
  fold_wino_ = Floats();
  if (kernels::winograd_applicable(s) && !spec_.transposed) {
    fold_wino_ = Floats(kernels::winograd_weight_floats(s));
    kernels::pack_winograd_weights(s, w.data(), fold_wino_.data());
  }
  fold_bias16_ = Floats(std::size_t((spec_.out + 15) / 16) * 16);
  for (int o = 0; o < spec_.out; ++o) fold_bias16_[o] = shift[o] + (bias ? scale[o] * bias->value[o] : 0.f);
  fold_bf16_.clear();  // packed from fold_w_ when first asked for
  fold_wino_bf16_.clear();  // from fold_wino_, likewise
  folded_ = true;
}

Conv2d::FoldedPath Conv2d::folded_path(const kernels::ConvShape& s, bool winograd) const {
  if (spec_.transposed) return FoldedPath::direct;
  if (takes_bf16(s)) return FoldedPath::amx;
  if (!winograd || !fold_wino_.size() || !winograd_allowed()) return FoldedPath::direct;
  if (kernels::winograd_bf16_pays(s) && bf16_path() == Bf16Path::winograd) return FoldedPath::winograd_bf16;
  return kernels::winograd_pays(s) ? FoldedPath::winograd : FoldedPath::direct;
}

void Conv2d::pack_winograd_bf16(const kernels::ConvShape& s) {
  if (!fold_wino_bf16_.empty()) return;
  fold_wino_bf16_.resize(kernels::winograd_bf16_weight_halves(s));
  kernels::pack_winograd_bf16_weights(s, fold_wino_.data(), fold_wino_bf16_.data());
}

void Conv2d::pack_amx_bf16(const kernels::ConvShape& s) {
  if (!fold_bf16_.empty()) return;
  Floats w(weight.numel());
  kernels::unpack_conv_weights(s, fold_w_.data(), w.data());
  fold_bf16_.resize(kernels::conv_bf16_weight_halves(s));
  kernels::pack_conv_bf16_weights(s, w.data(), fold_bf16_.data());
}

void Conv2d::forward_folded(const Act& x, const Act& y, const float* scale, const float* shift, bool winograd,
                            bool relu) {
  check_io(x, y);
  kernels::ConvShape s = conv_shape(x);
  pack_folded(s, scale, shift);
  const FoldedPath path = folded_path(s, winograd);
  if (path == FoldedPath::amx || path == FoldedPath::winograd_bf16) {
    s.relu = relu;
    record(x, y, s);
    if (path == FoldedPath::amx) {
      pack_amx_bf16(s);
      kernels::conv_fwd_bf16_amx(s, x.data, fold_bf16_.data(), fold_bias16_.data(), y.data);
    } else {
      pack_winograd_bf16(s);
      kernels::conv_fwd_winograd_bf16(s, x.data, fold_wino_bf16_.data(), fold_bias16_.data(), y.data);
    }
    return;
  }
  run_forward(x, y, fold_w_.data(), fold_wino_.size() ? fold_wino_.data() : nullptr, fold_bias16_.data(), winograd,
              relu);
}

bool Conv2d::forward_folded_cat(const Act& a, const Act& b, int top, int left, const Act& y, const float* scale,
                                const float* shift, bool relu) {
  const Act x{nullptr, a.n, a.c + b.c, a.h, a.w};
  check_io(x, y);
  kernels::ConvShape s = conv_shape(x);
  const kernels::ConcatInput in{a.data, a.c, b.data, b.c, b.h, b.w, top, left};
  if (b.n != a.n) return false;
  pack_folded(s, scale, shift);
  const FoldedPath path = folded_path(s, true);
  const bool in_place = path == FoldedPath::amx ? kernels::conv_bf16_cat_applicable(s, in)
                        : path == FoldedPath::direct ? false
                                                     : kernels::winograd_cat_applicable(s, in);
  if (!in_place) return false;
  s.relu = relu;
  record(x, y, s);
  if (path == FoldedPath::amx) {
    pack_amx_bf16(s);
    kernels::conv_fwd_bf16_amx_cat(s, in, fold_bf16_.data(), fold_bias16_.data(), y.data);
  } else if (path == FoldedPath::winograd_bf16) {
    pack_winograd_bf16(s);
    kernels::conv_fwd_winograd_bf16_cat(s, in, fold_wino_bf16_.data(), fold_bias16_.data(), y.data);
  } else {
    kernels::conv_kernels().fwd_winograd_cat(s, in, fold_wino_.data(), fold_bias16_.data(), y.data);
  }
  return true;
}

bool Conv2d::forward_folded_pair(const Act& a, const Act* b, int top, int left, const float* scale, const float* shift,
                                 bool relu, Conv2d& next, const float* next_scale, const float* next_shift,
                                 bool next_relu, const Act& y) {
  const Act x{nullptr, a.n, a.c + (b ? b->c : 0), a.h, a.w};
  check_io(x, out_shape(x));
  const Act mid = out_shape(x);
  next.check_io(mid, y);
  kernels::ConvShape s1 = conv_shape(x), s2 = next.conv_shape(mid);
  kernels::ConcatInput in{a.data, a.c};
  if (b) in = {a.data, a.c, b->data, b->c, b->h, b->w, top, left};
  if (spec_.transposed || next.spec_.transposed || !takes_bf16(s1) || !takes_bf16(s2) ||
      !kernels::conv_bf16_pair_applicable(s1, s2) || (b && (b->n != a.n || !kernels::conv_bf16_cat_applicable(s1, in))))
    return false;
  pack_folded(s1, scale, shift);
  next.pack_folded(s2, next_scale, next_shift);
  pack_amx_bf16(s1);
  next.pack_amx_bf16(s2);
  s1.relu = relu;
  s2.relu = next_relu;
  record(x, mid, s1);
  next.record(mid, y, s2);
  kernels::conv_pair_fwd_bf16_amx(s1, in, fold_bf16_.data(), fold_bias16_.data(), s2, next.fold_bf16_.data(),
                                  next.fold_bias16_.data(), y.data);
  return true;
}

void Conv2d::backward(const Act& x, const Act& dy, const Act* dx) {
  const auto s = conv_shape(x);
  const Act o = out_shape(x);
  check(dy, o.c, o.h, o.w, "output gradient");
  pack(s);
  const kernels::ConvKernels& k = kernels::conv_kernels();
  if (spec_.transposed) {
    const auto d = deconv_shape(x);
    if (dx) kernels::deconv_bwd_data(k, d, dy.data, fwd_.data(), dx->data);
    kernels::deconv_bwd_weights(k, d, x.data, dy.data, dw_packed_.data(), bias ? db16_.data() : nullptr);
  } else {
    if (dx) k.bwd_data(s, dy.data, bwd_.data(), nullptr, dx->data);
    k.bwd_weights(s, x.data, dy.data, dw_packed_.data(), bias ? db16_.data() : nullptr);
  }
  if (dw_plain_.size() != weight.numel()) dw_plain_ = Floats(weight.numel());
  kernels::unpack_conv_weights(s, dw_packed_.data(), dw_plain_.data());
  for (std::size_t i = 0; i < weight.numel(); ++i) weight.grad[i] += dw_plain_[i];
  if (bias)
    for (int c = 0; c < spec_.out; ++c) bias->grad[c] += db16_[c];
}

}  // namespace yelan::layers
