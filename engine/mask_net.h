// Stage 1 (SPEC 5): U-Net giving N mask logits (the current frame and N-1 future ones)
// and a confidence score each. Names as the reference: inc.double_conv.*,
// down<k>.maxpool_conv.1.double_conv.*, up<k>.up.* (ConvTranspose 2x2/2 with bias),
// up<k>.conv.double_conv.*, outc.conv.*, score_conv.{0,1}.*, fc.*.
#pragma once
#include <array>
#include <memory>
#include <vector>

#include "camera/pixel_rect.h"
#include "engine/model_config.h"
#include "layers/blocks.h"
#include "layers/module.h"

namespace yelan {

// conv3x3-BN-ReLU twice.
class DoubleConv : public layers::Module<DoubleConv> {
 public:
  DoubleConv(int in, int out) : a_({in, out, 3, 1, 1}, true), b_({out, out, 3, 1, 1}, true) {}
  static constexpr std::uint64_t kSeedStride = 2;
  template <class F>
  void for_each_part(F&& f) {
    f(a_, {"double_conv.0.", 1, "double_conv.1."});
    f(b_, {"double_conv.3.", 2, "double_conv.4."});
  }
  layers::Act forward(const layers::Act& x);
  // forward of [a, F.pad(b)], read in place where the first convolution can (ConvBn::forward_cat).
  layers::Act forward_cat(const layers::Act& a, const layers::Act& b, int top, int left);
  void backward(const layers::Act& x, const layers::Act& dy, const layers::Act& dx);

 private:
  layers::ConvBn a_, b_;
  layers::ActBuf da_;
};

class MaskNet : public layers::Module<MaskNet> {
 public:
  explicit MaskNet(const ModelConfig& cfg);
  // The parts in state_dict order (layers/module.h derives params, init, set_training and
  // weights_changed from this list).
  static constexpr std::uint64_t kSeedStride = 100;
  template <class F>
  void for_each_part(F&& f) {
    f(inc_, {"inc.", 1});
    for (int k = 0; k < kLevels; ++k) f(*down_[k], {"down" + std::to_string(k + 1) + ".maxpool_conv.1.", 10u + k});
    for (int k = 0; k < kLevels; ++k) {
      f(*up_[k], {"up" + std::to_string(k + 1) + ".up.", 20u + k});
      f(*up_conv_[k], {"up" + std::to_string(k + 1) + ".conv.", 30u + k});
    }
    f(outc_, {"outc.conv.", 40});
    f(score1_, {"score_conv.0.", 41});
    f(score2_, {"score_conv.1.", 42});
    f(fc_, {"fc.", 43});
  }

  // x: n frames, cfg.channels x H x W. Results valid until the next forward. Under NoGrad with
  // run.mask_mirror, the average of the net on x and on x mirrored (its masks mirrored back).
  void forward(const layers::Act& x);
  // After a plain forward on x (under NoGrad): x mirrored run too and the two averaged, as
  // run.mask_mirror does (yelan run calls it where run.mask_mirror's margin says).
  void add_mirror(const layers::Act& x);
  // Inference only (NoGrad, one frame): stage 1 computed only over `box` (input pixels; widened
  // to multiples of 16, the U-Net's grid) and its scaled copy at each level, grown by a halo of
  // kCropHalo cells. Every map elsewhere holds what an all-zero frame gives there (computed once
  // per weights): a convolution at the box's edge reads the empty room's features, not zero
  // padding, which no map of the frame holds (a net that sees the whole frame at its bottleneck
  // lost half its IoU on small crops padded with zeros). Exact where the frame is empty outside
  // the box but for the halo's truncation; the score head pools the frame so composed. Returns
  // the box run (the whole frame, forward() itself, where the box is empty, covers the frame,
  // or mask.pool > 1).
  using Box = camera::PixelRect;
  Box forward_cropped(const layers::Act& x, Box box);
  void weights_changed() {
    have_zero_ = false;
    Module::weights_changed();
  }
  // Inference in bf16 on AMX where the CPU has it (layers::bf16_convs). Off unless set: the
  // pipeline sets the model's run.bf16 (or --bf16); training and frame-by-frame eval run fp32.
  void set_bf16(bool on) { bf16_ = on; }
  bool bf16() const { return bf16_; }
  const layers::Act& masks() const { return masks_; }        // n x N logits x H x W
  const std::vector<float>& scores() const { return scores_; }  // n x N, after the sigmoid
  // dmasks: dL/dlogits (data may be null); dscores: dL/dscores (may be null).
  void backward(const layers::Act& x, const layers::Act& dmasks, const float* dscores);

 private:
  void check_input(const layers::Act& x) const;
  void forward_once(const layers::Act& x);
  // The U-Net from its input to the last up block's output (the map outc and the score head read).
  layers::Act unet_top(const layers::Act& in);
  // From top_gap_ (the top's mean per channel): the scores of n images.
  void score_head(int n);
  static constexpr int kLevels = 4;  // the U-Net's depth: 4 downs, 4 ups (the architecture's, not a config's)
  ModelConfig cfg_;
  bool bf16_ = false;
  int w_[kLevels + 1];
  DoubleConv inc_;
  std::vector<std::unique_ptr<DoubleConv>> down_, up_conv_;
  std::vector<std::unique_ptr<layers::Conv2d>> up_;
  std::vector<layers::MaxPool2d> pool_;
  layers::Conv2d outc_, score1_, score2_;
  layers::Linear fc_;

  // the last forward
  std::array<layers::Act, kLevels + 1> x_;  // inc output, down1..down4 outputs
  // padded_: the shapes of F.pad's maps alone (no data): concat_padded writes cat_ straight
  // from upt_; backward and the cropped run's empty frame make them from upt_ where needed.
  // Under NoGrad cat_ is a shape too: the up convolutions read skip and upt_ in place.
  std::array<layers::Act, kLevels> pooled_, upt_, padded_, cat_, upo_;
  std::array<int, kLevels> pad_top_{}, pad_left_{};
  layers::ActBuf pooled_buf_[kLevels], upt_buf_[kLevels], cat_buf_[kLevels];
  layers::ActBuf masks_buf_, top_gap_buf_, s1_buf_, gap_buf_;
  layers::ActBuf pooled_in_buf_, pooled_masks_buf_, d_pooled_masks_;  // mask.pool > 1 only
  layers::Act pooled_in_, pooled_masks_;
  layers::Act masks_, top_gap_, s1_, gap_;  // the score head: pooled top, then its two 1x1 convolutions
  std::vector<float> logits_, scores_;
  layers::ActBuf mirror_in_buf_, mirror_masks_buf_;  // run.mask_mirror only
  // forward_cropped (mask_net_crop.cpp): the zero frame's maps (z*) and the frame's as the last
  // cropped run left them (c*: the zero frame's but in the boxes `written` names), per level:
  // the down path's outputs (inc at 0), the up path's padded upsamples and outputs; the masks.
  static constexpr int kCropHalo = 2;
  void prepare_zero_frame(int channels);
  std::array<layers::ActBuf, kLevels + 1> zx_, cx_;
  std::array<layers::ActBuf, kLevels> zpad_, cpad_, zup_, cup_;
  layers::ActBuf zmask_, cmask_;
  std::array<Box, kLevels + 1> written_x_;
  std::array<Box, kLevels> written_pad_, written_up_;
  Box written_mask_;
  std::vector<float> zero_top_sum_;  // the zero frame's top, summed per channel over the frame
  layers::ActBuf win_a_, win_b_, win_out_, gap_win_;
  bool have_zero_ = false, cropped_ = false;
  bool zero_bf16_ = false;  // the precision the empty frame was computed at (layers::bf16_active)
  // backward only, each dL/d the activation it is named after
  layers::ActBuf d_top_;                      // the last up block's output (what outc and the score head read)
  layers::ActBuf d_gap_, d_s1_, d_top_gap_, d_top_score_;  // the score head; d_top_score_ is its share of d_top_
  layers::ActBuf d_cat_, d_padded_, d_upt_;  // one up level at a time
  layers::ActBuf d_pooled_;                  // one down level at a time
  layers::ActBuf d_skip_[kLevels];           // x_[k] as a skip, held until the down path reaches level k
  layers::ActBuf d_level_[2];                // the main path, ping-pong: an up or down block's input and output
};

}  // namespace yelan
