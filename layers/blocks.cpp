#include "layers/blocks.h"

#include <cmath>
#include <stdexcept>

namespace yelan::layers {

void ConvBn::params(const std::string& conv_key, const std::string& bn_key, ParamList& out) {
  conv.params(conv_key, out);
  bn.params(bn_key, out);
}

void ConvBn::fold() {
  const int c = conv.spec().out;
  if (scale_.size() != std::size_t(c)) scale_ = Floats(c), shift_ = Floats(c);
  for (int o = 0; o < c && !conv.fold_packed(); ++o) {
    scale_[o] = bn.weight.value[o] / std::sqrt(bn.running_var.value[o] + bn.eps);
    shift_[o] = bn.bias.value[o] - bn.running_mean.value[o] * scale_[o];
  }
}

Act ConvBn::forward(const Act& x) {
  const Act s = conv.out_shape(x);
  folded_ = !bn.training && !grad_enabled();
  if (folded_) {
    post_ = post_buf_.like(s);
    fold();
    // The ReLU in the convolution's store where the kernel has one (forward convolutions).
    const bool fuse = bn.fused_relu() && !conv.spec().transposed;
    conv.forward_folded(x, post_, scale_.data(), shift_.data(), true, fuse);
    if (bn.fused_relu() && !fuse) activation_forward(Activation::relu, post_, post_);
    return post_;
  }
  pre_ = pre_buf_.like(s);
  post_ = post_buf_.like(s);
  conv.forward(x, pre_, !bn.training);  // Winograd when only inference follows
  bn.forward(pre_, post_);
  return post_;
}

Act ConvBn::forward_cat(const Act& a, const Act& b, int top, int left) {
  if (!bn.training && !grad_enabled() && !conv.spec().transposed) {
    post_ = post_buf_.like(conv.out_shape(Act{nullptr, a.n, a.c + b.c, a.h, a.w}));
    fold();
    if (conv.forward_folded_cat(a, b, top, left, post_, scale_.data(), shift_.data(), bn.fused_relu())) {
      folded_ = true;
      return post_;
    }
  }
  const Act cat = cat_buf_.get(a.n, a.c + b.c, a.h, a.w);
  concat_padded(a, b, top, left, cat);
  return forward(cat);
}

Act ConvBn::forward_then(ConvBn& next, const Act& a, const Act* b, int top, int left) {
  if (!bn.training && !next.bn.training && !grad_enabled() && !conv.spec().transposed && !next.conv.spec().transposed) {
    const Act mid = conv.out_shape(Act{nullptr, a.n, a.c + (b ? b->c : 0), a.h, a.w});
    next.post_ = next.post_buf_.like(next.conv.out_shape(mid));
    fold();
    next.fold();
    if (conv.forward_folded_pair(a, b, top, left, scale_.data(), shift_.data(), bn.fused_relu(), next.conv,
                                 next.scale_.data(), next.shift_.data(), next.bn.fused_relu(), next.post_)) {
      folded_ = next.folded_ = true;
      post_ = mid;  // its shape: the values went to next in bf16
      return next.post_;
    }
  }
  return next.forward(b ? forward_cat(a, *b, top, left) : forward(a));
}

void ConvBn::backward(const Act& x, const Act& dy, const Act* dx) {
  if (folded_) throw std::logic_error("ConvBn: backward after a forward run under NoGrad");
  const Act dpre = dpre_buf_.like(pre_);
  bn.backward(pre_, post_, dy, dpre);
  conv.backward(x, dpre, dx);
}

namespace {
ConvSpec first_conv(int in, int out, ResidualKind kind, int oph, int opw) {
  switch (kind) {
    case ResidualKind::regular: return {in, out, 3, 1, 1};
    case ResidualKind::down: return {in, out, 3, 2, 1};
    case ResidualKind::up: return {in, out, 3, 2, 1, false, true, oph, opw};
  }
  return {};
}
ConvSpec shortcut_conv(int in, int out, ResidualKind kind, int oph, int opw) {
  switch (kind) {
    case ResidualKind::regular: return {in, out, 1, 1, 0};
    case ResidualKind::down: return {in, out, 1, 2, 0};
    case ResidualKind::up: return {in, out, 1, 2, 0, false, true, oph, opw};
  }
  return {};
}
}  // namespace

ResidualBlock::ResidualBlock(int in, int out, ResidualKind kind, int oph, int opw)
    : a_(first_conv(in, out, kind, oph, opw), true),
      b_({out, out, 3, 1, 1}, true),
      shortcut_(shortcut_conv(in, out, kind, oph, opw), false) {}

void ResidualBlock::params(const std::string& p, ParamList& out) {
  a_.params(p + "module.0.", p + "module.1.", out);
  b_.params(p + "module.3.", p + "module.4.", out);
  shortcut_.params(p + "shortcut.0.", p + "shortcut.1.", out);
}

void ResidualBlock::init(std::uint64_t seed) {
  a_.init(seed * 3 + 1);
  b_.init(seed * 3 + 2);
  shortcut_.init(seed * 3 + 3);
}

void ResidualBlock::set_training(bool on) {
  a_.set_training(on);
  b_.set_training(on);
  shortcut_.set_training(on);
}

void ResidualBlock::weights_changed() {
  a_.weights_changed();
  b_.weights_changed();
  shortcut_.weights_changed();
}

Act ResidualBlock::forward(const Act& x) {
  const Act a = a_.forward(x);
  const Act b = b_.forward(a);
  const Act s = shortcut_.forward(x);
  const Act y = y_buf_.like(b);
  add_forward(b, s, y);
  return y;
}

void ResidualBlock::backward(const Act& x, const Act& dy, const Act& dx) {
  const Act da = dtmp_buf_.like(a_.out());
  b_.backward(a_.out(), dy, &da);
  a_.backward(x, da, &dx);
  const Act dsc = dsc_buf_.like(x);
  shortcut_.backward(x, dy, &dsc);
  accumulate(dsc, dx);
}

BasicBlock::BasicBlock(int in, int out, int stride) : a_({in, out, 3, stride, 1}, true), b_({out, out, 3, 1, 1}, false) {
  if (stride != 1 || in != out) down_ = std::make_unique<ConvBn>(ConvSpec{in, out, 1, stride, 0}, false);
}

void BasicBlock::params(const std::string& p, ParamList& out) {
  a_.params(p + "conv1.", p + "bn1.", out);
  b_.params(p + "conv2.", p + "bn2.", out);
  if (down_) down_->params(p + "downsample.0.", p + "downsample.1.", out);
}

void BasicBlock::init(std::uint64_t seed) {
  a_.init(seed * 3 + 1);
  b_.init(seed * 3 + 2);
  if (down_) down_->init(seed * 3 + 3);
}

void BasicBlock::set_training(bool on) {
  a_.set_training(on);
  b_.set_training(on);
  if (down_) down_->set_training(on);
}

void BasicBlock::weights_changed() {
  a_.weights_changed();
  b_.weights_changed();
  if (down_) down_->weights_changed();
}

Act BasicBlock::forward(const Act& x) {
  const Act a = a_.forward(x);
  const Act b = b_.forward(a);
  const Act identity = down_ ? down_->forward(x) : x;
  y_ = y_buf_.like(b);
  add_forward(b, identity, y_);
  activation_forward(Activation::relu, y_, y_);
  return y_;
}

void BasicBlock::backward(const Act& x, const Act& dy, const Act& dx) {
  const Act dsum = dsum_buf_.like(y_);
  activation_backward(Activation::relu, y_, dy, dsum);
  const Act da = dtmp_buf_.like(a_.out());
  b_.backward(a_.out(), dsum, &da);
  a_.backward(x, da, &dx);
  if (down_) {
    const Act dds = dds_buf_.like(x);
    down_->backward(x, dsum, &dds);
    accumulate(dds, dx);
  } else {
    accumulate(dsum, dx);
  }
}

}  // namespace yelan::layers
