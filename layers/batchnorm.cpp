#include "layers/batchnorm.h"

#include <cmath>
#include <stdexcept>
#include <string>

#include "kernels/bn.h"

namespace yelan::layers {

BatchNorm2d::BatchNorm2d(int channels, bool fused_relu)
    : weight("weight", {channels}),
      bias("bias", {channels}),
      running_mean("running_mean", {channels}, false),
      running_var("running_var", {channels}, false),
      num_batches_tracked("num_batches_tracked", {}, false),
      c_(channels),
      relu_(fused_relu) {
  const std::size_t padded = std::size_t((channels + 15) / 16) * 16;
  for (int i = 0; i < channels; ++i) {
    weight.value[i] = 1.f;
    running_var.value[i] = 1.f;
  }
  mean_ = Floats(padded);
  var_ = Floats(padded);
  gamma16_ = Floats(padded);
  beta16_ = Floats(padded);
  dg_ = Floats(padded);
  db_ = Floats(padded);
}

void BatchNorm2d::params(const std::string& prefix, ParamList& out) {
  for (Param* p : {&weight, &bias, &running_mean, &running_var, &num_batches_tracked}) out.push_back({prefix + p->name, p});
}

void BatchNorm2d::pad_affine() {
  for (int i = 0; i < c_; ++i) {
    gamma16_[i] = weight.value[i];
    beta16_[i] = bias.value[i];
  }
}

void BatchNorm2d::forward(const Act& x, const Act& y) {
  if (x.c != c_ || y.c != c_ || x.h != y.h || x.w != y.w || x.n != y.n)
    throw std::invalid_argument("batchnorm: expected " + std::to_string(c_) + " channels in and out, got " +
                                std::to_string(x.c) + " -> " + std::to_string(y.c));
  const kernels::BnKernels& k = kernels::bn_kernels();
  const kernels::BnShape s{x.n, x.cb(), x.pixels()};
  pad_affine();
  if (training) {
    k.stats(s, x.data, mean_.data(), var_.data());
    const double m = double(x.n) * x.pixels();
    const double unbias = m > 1 ? m / (m - 1) : 1.0;
    for (int i = 0; i < c_; ++i) {
      running_mean.value[i] = (1 - momentum) * running_mean.value[i] + momentum * mean_[i];
      running_var.value[i] = float((1 - momentum) * running_var.value[i] + momentum * var_[i] * unbias);
    }
    num_batches_tracked.value[0] += 1.f;
  } else {
    for (int i = 0; i < c_; ++i) {
      mean_[i] = running_mean.value[i];
      var_[i] = running_var.value[i];
    }
  }
  k.fwd(s, x.data, mean_.data(), var_.data(), gamma16_.data(), beta16_.data(), eps, relu_, y.data);
}

void BatchNorm2d::backward(const Act& x, const Act& y, const Act& dy, const Act& dx) {
  const kernels::BnShape s{x.n, x.cb(), x.pixels()};
  if (training) {
    kernels::bn_kernels().bwd(s, x.data, y.data, dy.data, mean_.data(), var_.data(), gamma16_.data(), eps, relu_,
                              dx.data, dg_.data(), db_.data());
  } else {  // fixed statistics: an affine map per channel
    dg_.zero();
    db_.zero();
    for (int n = 0; n < x.n; ++n)
      for (int b = 0; b < x.cb(); ++b)
        for (std::size_t p = 0; p < x.pixels(); ++p)
          for (int l = 0; l < 16; ++l) {
            const int ch = b * 16 + l;
            const std::size_t i = ((std::size_t(n) * x.cb() + b) * x.pixels() + p) * 16 + l;
            const float inv = ch < c_ ? 1.f / std::sqrt(var_[ch] + eps) : 0.f;
            const float g = relu_ && !(y.data[i] > 0.f) ? 0.f : dy.data[i];
            dg_[ch] += g * (x.data[i] - mean_[ch]) * inv;
            db_[ch] += g;
            dx.data[i] = g * gamma16_[ch] * inv;
          }
  }
  for (int i = 0; i < c_; ++i) {
    weight.grad[i] += dg_[i];
    bias.grad[i] += db_[i];
  }
}

}  // namespace yelan::layers
