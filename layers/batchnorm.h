// BatchNorm2d (PyTorch semantics: momentum 0.1, eps 1e-5, biased batch variance for
// normalising, unbiased for the running average), with an optional fused ReLU.
#pragma once
#include <cstdint>

#include "layers/param.h"

namespace yelan::layers {

class BatchNorm2d {
 public:
  explicit BatchNorm2d(int channels, bool fused_relu = false);

  Param weight, bias, running_mean, running_var, num_batches_tracked;
  bool training = true;
  void set_training(bool on) { training = on; }
  float eps = 1e-5f, momentum = 0.1f;

  void params(const std::string& prefix, ParamList& out);
  void forward(const Act& x, const Act& y);
  // Training mode: through the batch statistics of the last forward. Adds to the
  // weight/bias gradients; writes dx. y is the forward output (ReLU mask).
  void backward(const Act& x, const Act& y, const Act& dy, const Act& dx);
  bool fused_relu() const { return relu_; }

 private:
  int c_;
  bool relu_;
  Floats mean_, var_, gamma16_, beta16_, dg_, db_;  // per-channel, padded to blocks of 16
  void pad_affine();
};

}  // namespace yelan::layers
