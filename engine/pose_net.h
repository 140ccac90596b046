// Stage 2 (SPEC 5): ResNet34 head -> window ConvLSTM -> skip block -> stacked hourglasses
// giving xy/zy/xz marginal heatmaps per stage -> DSNT joints from the last stage. The
// state_dict keys are the reference's (weights_tools/README.md): in_cnn.*, cl.*,
// cl_skip_block.*, {xy,zy,xz}_hm_cnns.<stage>.*, hm_combiners.<stage-1>.*.
#pragma once
#include <array>
#include <memory>
#include <vector>

#include "camera/pixel_rect.h"
#include "engine/model_config.h"
#include "layers/blocks.h"
#include "layers/convlstm.h"
#include "layers/hourglass.h"
#include "layers/module.h"

namespace yelan {

class PoseNet : public layers::Module<PoseNet> {
 public:
  explicit PoseNet(const ModelConfig& cfg);
  // The parts in state_dict order (layers/module.h derives params, init, set_training and
  // weights_changed from this list).
  static constexpr std::uint64_t kSeedStride = 1000;
  template <class F>
  void for_each_part(F&& f) {
    f(conv1_, {"in_cnn.0.", 1});
    f(bn1_, {"in_cnn.1."});
    for (std::size_t i = 0; i < resnet_.size(); ++i)  // torchvision's layer1 (3 blocks), then layer2's first 4
      f(*resnet_[i], {i < 3 ? "in_cnn.4." + std::to_string(i) + "." : "in_cnn.5." + std::to_string(i - 3) + ".", 10 + i});
    if (cfg_.convlstm) f(cl_, {"cl.", 20});
    f(skip_, {"cl_skip_block.", 21});
    static const char* const plane_names[3] = {"xy_hm_cnns.", "zy_hm_cnns.", "xz_hm_cnns."};
    for (int p = 0; p < 3; ++p)
      for (int t = 0; t < cfg_.stages; ++t) f(*stages_[t].planes[p], {plane_names[p] + std::to_string(t) + ".", 100u + 3 * t + p});
    for (int t = 1; t < cfg_.stages; ++t)
      f(*stages_[t].combiner, {"hm_combiners." + std::to_string(t - 1) + ".combine_block.", 200u + t - 1});
    if (cfg_.depth_map)
      for (int t = 0; t < cfg_.stages; ++t) f(*stages_[t].depth, {"depth_hm_cnns." + std::to_string(t) + ".", 300u + t});
  }
  void weights_changed() {
    have_zero_feat_ = false;
    Module::weights_changed();
  }
  // Causal configs only: each forward continues the ConvLSTM state of the previous one (a
  // live stream fed a frame at a time); reset_stream() starts a new window.
  void set_streaming(bool on) { cl_.set_streaming(on); }
  void reset_stream() { cl_.reset_state(); }

  // x: B windows of S frames (frame t of window b is image b*S + t), cfg.channels x H x W.
  void forward(const layers::Act& x, int frames_per_window);

  // Model-input pixels [x0, x1) x [y0, y1); empty: nothing but zeros in the input.
  using CropBox = camera::PixelRect;
  // Inference only: forward() for an input that is zero outside `box` (a masked frame).
  // The ResNet head runs on the box widened to multiples of its stride (pose.head_stride), so the crop's
  // pixel grid is the frame's; elsewhere its features are those of an all-zero frame
  // (computed once per weights). Exact but for the head's receptive field reaching past the
  // crop, which the caller's margin around the mask bounds (yelan bench crop measures it).
  // Returns the box the head ran on (empty when it did not run).
  CropBox forward_cropped(const layers::Act& x, CropBox box, int frames_per_window);
  // Probability maps of stage t, plane p (0 xy, 1 zy, 2 xz), and normalised joints
  // (n x J x 3) of the last stage, valid until the next forward.
  const layers::Act& heatmap(int stage, int plane) const { return stages_[stage].probs[plane]; }
  const std::vector<float>& joints() const { return joints_; }
  // Stage t's depth maps (pose.depth_map; null without), valid until the next forward.
  const layers::Act* depth_map(int stage) const { return cfg_.depth_map ? &stages_[stage].depth_out : nullptr; }
  // Stage t's normalised joints (n x J x 3): x, y from its xy map; z from its zy and xz maps,
  // or from its depth map under its xy map (pose.depth_map). joints() is the last stage's.
  void stage_joints(int stage, float* out) const;
  // The ResNet head's output (n x resnet_mid x mid_h x mid_w) of the last forward.
  const layers::Act& head_features() const { return feats_; }
  int mid_h() const { return mid_h_; }
  int mid_w() const { return mid_w_; }

  // dL/d a stage's xy, zy and xz probability maps and, with pose.depth_map, its depth map.
  using StageGrads = std::array<layers::Act, 4>;
  // dheat[t][p]: dL/d stage t's map p (data may be null: no direct loss there); djoints:
  // dL/djoints (may be null). Adds every parameter's gradient.
  void backward(const layers::Act& x, const std::vector<StageGrads>& dheat, const float* djoints);

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

  // One hourglass stage: its parts, its activations of the last forward and its heatmaps'
  // gradients in the backward. stages_ has cfg.stages of them.
  struct Stage {
    std::unique_ptr<layers::ResidualBlock> combiner;  // stages after the first: over the previous heatmaps
    std::array<std::unique_ptr<layers::HourglassStage>, 3> planes;  // xy, zy, xz
    std::unique_ptr<layers::HourglassStage> depth;                   // pose.depth_map only
    layers::Act depth_out;                                           // its output: the depth maps
    layers::ActBuf hmcat_buf, inp_buf, prob_buf[3], dprob_buf[3], ddepth_buf;
    layers::Act hmcat;  // cat[xy, zy, xz] of the previous stage's heatmaps: the combiner's input
    layers::Act inp;    // the hourglasses' input: the skip block's output, plus the combiner's after the first
    std::array<layers::Act, 3> logits, probs;
  };
  std::vector<Stage> stages_;

  // activations of the last forward
  layers::ActBuf c1_buf_, b1_buf_, p_buf_, cat_buf_;
  layers::Act c1_, b1_, pooled_, cat_;
  std::vector<layers::Act> res_in_;  // input of each BasicBlock, then the head's output
  layers::Act feats_, cl_out_;
  std::vector<float> joints_;
  // Shared by forward and backward on purpose: cat[xy, zy] of a stage's heatmaps, in the
  // forward the probabilities on their way into hmcat (concatenated two at a time), in the
  // backward their gradient on its way out of it. Same shape, and live only within one stage.
  layers::ActBuf heat_pair_;
  // forward_cropped: the head's features for an all-zero frame, the crop and the full map
  layers::ActBuf zero_feat_buf_, crop_buf_, full_feat_buf_;
  bool have_zero_feat_ = false, cropped_ = false;
  bool zero_feat_bf16_ = false;  // the precision zero_feat_buf_ was made in (layers::bf16_active)
  // backward only, each dL/d the activation it is named after
  layers::ActBuf d_inp_;            // a stage's input (every stage adds to the next one's)
  layers::ActBuf d_dsnt_[3];        // the last stage's probabilities through the joints (xy, zy, xz)
  layers::ActBuf d_depth_joints_;   // the last stage's depth maps through the joints
  layers::ActBuf d_logits_, d_hg_in_;  // one plane at a time: its logits, its hourglass's input
  layers::ActBuf d_hmcat_;          // a combiner's input
  layers::ActBuf d_cat_;            // the skip block's input cat[feats, convlstm(feats)]
  layers::ActBuf d_cl_out_, d_c1_, d_b1_;
  layers::ActBuf d_feat_a_, d_feat_b_;  // the head's features, then ping-pong down its BasicBlocks
};

}  // namespace yelan
