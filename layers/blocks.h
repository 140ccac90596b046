// The composite blocks of SPEC section 5, with the reference code's state_dict names:
//   ConvBn         conv (no bias) + BatchNorm2d, optional fused ReLU; under NoGrad with BN in
//                  eval mode, the BN is folded into the conv's weights and bias (one pass)
//   ResidualBlock  module.{0,1,3,4} = conv-BN-ReLU-conv3x3-BN-ReLU, shortcut.{0,1} = conv-BN,
//                  summed (no ReLU after the sum); regular / down (stride 2) / up (transposed)
//   BasicBlock     torchvision's: conv1 bn1 relu conv2 bn2 (+ downsample.{0,1}), ReLU after the sum
// Each block keeps what its backward needs from the last forward (one input at a time).
#pragma once
#include <memory>
#include <string>

#include "layers/batchnorm.h"
#include "layers/buffer.h"
#include "layers/conv2d.h"
#include "layers/simple.h"

namespace yelan::layers {

class ConvBn {
 public:
  ConvBn(const ConvSpec& conv, bool relu) : conv(conv), bn(conv.out, relu) {}
  Conv2d conv;
  BatchNorm2d bn;
  void params(const std::string& conv_key, const std::string& bn_key, ParamList& out);
  void init(std::uint64_t seed) { conv.init(seed); }
  void set_training(bool on) {
    bn.training = on;
    conv.fold_changed();  // the running statistics may have moved since the last fold
  }
  void weights_changed() { conv.weights_changed(); }
  Act forward(const Act& x);  // the output lives in this unit until its next forward
  // forward of [a, F.pad(b)] (layers::concat_padded's): under NoGrad in eval mode read in place
  // where the convolution is a Winograd or AMX one, else concatenated into this unit's buffer first.
  Act forward_cat(const Act& a, const Act& b, int top, int left);
  // next.forward(forward(x)) and next.forward(forward_cat(a, b, ...)): under NoGrad in eval mode
  // one AMX kernel where both convolutions run in bf16 there (Conv2d::forward_folded_pair; this
  // unit's output then is not kept: out() holds its shape alone). The output lives in next.
  Act forward_pair(ConvBn& next, const Act& x) { return forward_then(next, x, nullptr, 0, 0); }
  Act forward_cat_pair(ConvBn& next, const Act& a, const Act& b, int top, int left) {
    return forward_then(next, a, &b, top, left);
  }
  void backward(const Act& x, const Act& dy, const Act* dx);
  const Act& out() const { return post_; }

 private:
  ActBuf pre_buf_, post_buf_, dpre_buf_, cat_buf_;
  Act pre_, post_;
  bool folded_ = false;  // the last forward ran BN folded into the conv (no backward possible)
  Floats scale_, shift_;
  void fold();  // scale_ and shift_ from the BatchNorm's running statistics, unless packed
  Act forward_then(ConvBn& next, const Act& a, const Act* b, int top, int left);
};

enum class ResidualKind { regular, down, up };

class ResidualBlock {
 public:
  ResidualBlock(int in, int out, ResidualKind kind, int out_pad_h = 0, int out_pad_w = 0);
  void params(const std::string& prefix, ParamList& out);
  void init(std::uint64_t seed);
  void set_training(bool on);
  void weights_changed();
  Act out_shape(const Act& x) const { return a_.conv.out_shape(x); }
  Act forward(const Act& x);
  void backward(const Act& x, const Act& dy, const Act& dx);

 private:
  ConvBn a_, b_, shortcut_;
  ActBuf y_buf_, dtmp_buf_, dsc_buf_;
};

class BasicBlock {
 public:
  BasicBlock(int in, int out, int stride);
  void params(const std::string& prefix, ParamList& out);
  void init(std::uint64_t seed);
  void set_training(bool on);
  void weights_changed();
  Act forward(const Act& x);
  void backward(const Act& x, const Act& dy, const Act& dx);

 private:
  ConvBn a_, b_;
  std::unique_ptr<ConvBn> down_;
  ActBuf y_buf_, dsum_buf_, dtmp_buf_, dds_buf_;
  Act y_;
};

}  // namespace yelan::layers
