// Stage 2 (SPEC 5): ResNet34 head -> window ConvLSTM -> skip block -> stacked hourglasses
// giving xy/zy/xz marginal heatmaps per stage -> DSNT joints from the last stage. The
// state_dict keys are the reference's (weights_tools/README.md): in_cnn.*, cl.*,
// cl_skip_block.*, {xy,zy,xz}_hm_cnns.<stage>.*, hm_combiners.<stage-1>.*.
#pragma once
#include <array>
#include <memory>
#include <vector>

#include "engine/model_config.h"
#include "layers/blocks.h"
#include "layers/convlstm.h"
#include "layers/hourglass.h"

namespace yelan {

class PoseNet {
 public:
  explicit PoseNet(const ModelConfig& cfg);
  void params(layers::ParamList& out);
  void init(std::uint64_t seed);
  void set_training(bool on);
  void weights_changed();
  // Causal configs only: each forward continues the ConvLSTM state of the previous one (a
  // live stream fed a frame at a time); reset_stream() starts a new window.
  void set_streaming(bool on) { cl_.set_streaming(on); }
  void reset_stream() { cl_.reset_state(); }

  // x: B windows of S frames (frame t of window b is image b*S + t), cfg.channels x H x W.
  void forward(const layers::Act& x, int frames_per_window);

  // Model-input pixels [x0, x1) x [y0, y1); empty: nothing but zeros in the input.
  struct CropBox {
    int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
    bool empty() const { return x1 <= x0 || y1 <= y0; }
  };
  // Inference only: forward() for an input that is zero outside `box` (a masked frame).
  // The ResNet head runs on the box widened to multiples of 8, its stride, so the crop's
  // pixel grid is the frame's; elsewhere its features are those of an all-zero frame
  // (computed once per weights). Exact but for the head's receptive field reaching past the
  // crop, which the caller's margin around the mask bounds (yelan bench crop measures it).
  // Returns the box the head ran on (empty when it did not run).
  CropBox forward_cropped(const layers::Act& x, CropBox box, int frames_per_window);
  // Probability maps of stage t, plane p (0 xy, 1 zy, 2 xz), and normalised joints
  // (n x J x 3) of the last stage, valid until the next forward.
  const layers::Act& heatmap(int stage, int plane) const { return probs_[stage][plane]; }
  const std::vector<float>& joints() const { return joints_; }
  // The ResNet head's output (n x resnet_mid x mid_h x mid_w) of the last forward.
  const layers::Act& head_features() const { return feats_; }
  int mid_h() const { return mid_h_; }
  int mid_w() const { return mid_w_; }

  // dheat[t][p]: dL/d probability map (data may be null: no direct loss there); djoints:
  // dL/djoints (may be null). Adds every parameter's gradient.
  void backward(const layers::Act& x, const std::vector<std::array<layers::Act, 3>>& dheat, const float* djoints);

 private:
  void check_input(const layers::Act& x) const;
  layers::Act head_forward(const layers::Act& x);  // conv1 .. the last BasicBlock
  void tail_forward(const layers::Act& feats, int n);  // ConvLSTM .. joints

  ModelConfig cfg_;
  int mid_h_, mid_w_, S_ = 1;
  layers::Conv2d conv1_;
  layers::BatchNorm2d bn1_;
  layers::MaxPool2d pool_;
  std::vector<std::unique_ptr<layers::BasicBlock>> resnet_;
  layers::WindowConvLSTM cl_;
  layers::ResidualBlock skip_;
  std::vector<std::array<std::unique_ptr<layers::HourglassStage>, 3>> hourglass_;
  std::vector<std::unique_ptr<layers::ResidualBlock>> combiners_;

  // activations of the last forward
  layers::ActBuf c1_buf_, b1_buf_, p_buf_, cat_buf_, hmcat_buf_[8], inp_buf_[8], prob_buf_[8][3];
  layers::Act c1_, b1_, pooled_, cat_;
  std::vector<layers::Act> res_in_;  // input of each BasicBlock, then the head's output
  layers::Act feats_, cl_out_;
  std::vector<layers::Act> inp_, hmcat_;
  std::vector<std::array<layers::Act, 3>> logits_, probs_;
  std::vector<float> joints_;
  // forward_cropped: the head's features for an all-zero frame, the crop and the full map
  layers::ActBuf zero_feat_buf_, crop_buf_, full_feat_buf_;
  bool have_zero_feat_ = false, cropped_ = false;
  // gradient scratch
  layers::ActBuf g_inp_, g_prob_, g_logit_, g_hg_, g_cat_, g_extra_[8][3], g_feat_a_, g_feat_b_, g_cl_, g_c1_, g_b1_;
};

}  // namespace yelan
