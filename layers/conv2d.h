// Conv2d and ConvTranspose2d (PyTorch semantics, dilation 1, groups 1) on the conv
// kernels. Weights live in PyTorch's layout; packed copies for the kernels are rebuilt
// lazily after weights_changed() (a load or an optimizer step), never per call.
#pragma once
#include <cstdint>
#include <memory>

#include "kernels/conv.h"
#include "layers/param.h"

namespace yelan::layers {

struct ConvSpec {
  int in = 1, out = 1, k = 1, stride = 1, pad = 0;
  bool bias = false;
  bool transposed = false;  // ConvTranspose2d: weight (in, out, k, k)
  int out_pad_h = 0, out_pad_w = 0;
};

// Multiply-add FLOPs of every Conv2d forward since the last reset (`conv_flops() = 0`):
// what `yelan model summary` reports. Not thread-safe; a diagnostic.
std::uint64_t& conv_flops();

class Conv2d {
 public:
  explicit Conv2d(const ConvSpec& spec);

  Param weight;
  std::unique_ptr<Param> bias;

  void params(const std::string& prefix, ParamList& out);
  void init(std::uint64_t seed);  // PyTorch's default initialisation
  void weights_changed() { packed_ = false; }
  const ConvSpec& spec() const { return spec_; }

  // Output geometry for an input (data left null).
  Act out_shape(const Act& x) const;
  // y must have out_shape(x)'s size. Winograd only where applicable (3x3/1) and asked for.
  void forward(const Act& x, const Act& y, bool winograd = false);
  // Adds dL/dweight (and dL/dbias) to the gradients; writes dx when dx is non-null.
  void backward(const Act& x, const Act& dy, const Act* dx);

 private:
  ConvSpec spec_;
  bool packed_ = false;
  Floats fwd_, bwd_, wino_, bias16_, dw_packed_, db16_, dw_plain_;
  kernels::ConvShape conv_shape(const Act& x) const;   // the kernel's conv (for a deconv: its adjoint)
  kernels::DeconvShape deconv_shape(const Act& x) const;
  void pack(const kernels::ConvShape& s);
};

}  // namespace yelan::layers
