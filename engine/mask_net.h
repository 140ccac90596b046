// Stage 1 (SPEC 5): U-Net giving N mask logits (the current frame and N-1 future ones)
// and a confidence score each. Names as the reference: inc.double_conv.*,
// down<k>.maxpool_conv.1.double_conv.*, up<k>.up.* (ConvTranspose 2x2/2 with bias),
// up<k>.conv.double_conv.*, outc.conv.*, score_conv.{0,1}.*, fc.*.
#pragma once
#include <array>
#include <memory>
#include <vector>

#include "engine/model_config.h"
#include "layers/blocks.h"

namespace yelan {

// conv3x3-BN-ReLU twice.
class DoubleConv {
 public:
  DoubleConv(int in, int out) : a_({in, out, 3, 1, 1}, true), b_({out, out, 3, 1, 1}, true) {}
  void params(const std::string& prefix, layers::ParamList& out);
  void init(std::uint64_t seed);
  void set_training(bool on);
  void weights_changed();
  layers::Act forward(const layers::Act& x);
  void backward(const layers::Act& x, const layers::Act& dy, const layers::Act& dx);

 private:
  layers::ConvBn a_, b_;
  layers::ActBuf da_;
};

class MaskNet {
 public:
  explicit MaskNet(const ModelConfig& cfg);
  void params(layers::ParamList& out);
  void init(std::uint64_t seed);
  void set_training(bool on);
  void weights_changed();

  // x: n frames, cfg.channels x H x W. Results valid until the next forward.
  void forward(const layers::Act& x);
  const layers::Act& masks() const { return masks_; }        // n x N logits x H x W
  const std::vector<float>& scores() const { return scores_; }  // n x N, after the sigmoid
  // dmasks: dL/dlogits (data may be null); dscores: dL/dscores (may be null).
  void backward(const layers::Act& x, const layers::Act& dmasks, const float* dscores);

 private:
  ModelConfig cfg_;
  int w_[5];
  DoubleConv inc_;
  std::vector<std::unique_ptr<DoubleConv>> down_, up_conv_;
  std::vector<std::unique_ptr<layers::Conv2d>> up_;
  std::vector<layers::MaxPool2d> pool_;
  layers::Conv2d outc_, score1_, score2_;
  layers::Linear fc_;

  // the last forward
  std::array<layers::Act, 5> x_;          // inc output, down1..down4 outputs
  std::array<layers::Act, 4> pooled_, upt_, padded_, cat_, upo_;
  std::array<int, 4> pad_top_{}, pad_left_{};
  layers::ActBuf pooled_buf_[4], upt_buf_[4], padded_buf_[4], cat_buf_[4], masks_buf_, s1_buf_, s2_buf_, gap_buf_;
  layers::Act masks_, s1_, s2_, gap_;
  std::vector<float> logits_, scores_;
  // gradient scratch
  layers::ActBuf g_[8], skip_grad_[4], ping_[2];
};

}  // namespace yelan
