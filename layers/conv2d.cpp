#include "layers/conv2d.h"

#include <stdexcept>
#include <string>

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

void Conv2d::forward(const Act& x, const Act& y, bool winograd) {
  const auto s = conv_shape(x);
  const Act o = out_shape(x);
  check(x, spec_.in, x.h, x.w, "input");
  check(y, o.c, o.h, o.w, "output");
  if (!s.valid()) throw std::invalid_argument("conv: input " + std::to_string(x.h) + "x" + std::to_string(x.w) + " too small");
  pack(s);
  conv_flops() += std::uint64_t(s.flops());
  const kernels::ConvKernels& k = kernels::conv_kernels();
  const float* b = bias ? bias16_.data() : nullptr;
  if (spec_.transposed)
    kernels::deconv_fwd(k, deconv_shape(x), x.data, bwd_.data(), b, y.data);
  else if (winograd && wino_.size())
    k.fwd_winograd(s, x.data, wino_.data(), b, y.data);
  else
    k.fwd(s, x.data, fwd_.data(), b, y.data);
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
    if (dx) k.bwd_data(s, dy.data, bwd_.data(), dx->data);
    k.bwd_weights(s, x.data, dy.data, dw_packed_.data(), bias ? db16_.data() : nullptr);
  }
  if (dw_plain_.size() != weight.numel()) dw_plain_ = Floats(weight.numel());
  kernels::unpack_conv_weights(s, dw_packed_.data(), dw_plain_.data());
  for (std::size_t i = 0; i < weight.numel(); ++i) weight.grad[i] += dw_plain_[i];
  if (bias)
    for (int c = 0; c < spec_.out; ++c) bias->grad[c] += db16_[c];
}

}  // namespace yelan::layers
