#include "engine/mask_net.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "layers/resample.h"
#include "layers/simple.h"

namespace yelan {

using layers::Act;

namespace {

void zero(const Act& a) { std::memset(a.data, 0, a.floats() * sizeof(float)); }

// The adjoint: crops the window back out.
void crop_from(const Act& big, const Act& small, int top, int left) {
  layers::copy_window(big, top, left, small, 0, 0, small.h, small.w);
}

}  // namespace

Act DoubleConv::forward(const Act& x) { return a_.forward_pair(b_, x); }
Act DoubleConv::forward_cat(const Act& a, const Act& b, int top, int left) {
  return a_.forward_cat_pair(b_, a, b, top, left);
}
void DoubleConv::backward(const Act& x, const Act& dy, const Act& dx) {
  const Act da = da_.like(a_.out());
  b_.backward(a_.out(), dy, &da);
  a_.backward(x, da, dx.data ? &dx : nullptr);  // no dx wanted: skip backward-data
}

MaskNet::MaskNet(const ModelConfig& cfg)
    : cfg_(cfg),
      w_{cfg.unet_width(0), cfg.unet_width(1), cfg.unet_width(2), cfg.unet_width(3), cfg.unet_width(4)},
      inc_(cfg.channels, w_[0]),
      outc_({w_[0], cfg.n_masks, 1, 1, 0, true}),
      score1_({w_[0], 4 * w_[0], 1, 1, 0, true}),
      score2_({4 * w_[0], 8 * w_[0], 1, 1, 0, true}),
      fc_(8 * w_[0], cfg.n_masks) {
  for (int k = 0; k < kLevels; ++k)
    if (w_[k + 1] != 2 * w_[k])
      throw ConfigError(cfg.name + ": U-Net widths must double level to level (mask.width_mult x 64 an integer)");
  for (int k = 0; k < kLevels; ++k) {
    pool_.emplace_back(2, 2, 0);
    down_.push_back(std::make_unique<DoubleConv>(w_[k], w_[k + 1]));
  }
  for (int k = 0; k < kLevels; ++k) {  // up1 works on the deepest level
    const int cin = w_[kLevels - k];
    up_.push_back(std::make_unique<layers::Conv2d>(layers::ConvSpec{cin, cin / 2, 2, 2, 0, true, true}));
    up_conv_.push_back(std::make_unique<DoubleConv>(cin, w_[kLevels - 1 - k]));
  }
}

void MaskNet::forward(const Act& x) {
  forward_once(x);
  if (cfg_.mask_mirror && !layers::grad_enabled()) add_mirror(x);
}

void MaskNet::add_mirror(const Act& x) {
  if (layers::grad_enabled()) throw std::logic_error("mask net: the mirrored run is for inference (NoGrad)");
  // The net trained on mirrored windows (--flip) answers both; their mean cancels part of
  // what it gets wrong on one side only. Logits average (not probabilities): one cut for both.
  const Act first = mirror_masks_buf_.like(masks_);
  std::copy(masks_.data, masks_.data + masks_.floats(), first.data);
  const std::vector<float> first_logits = logits_;
  const Act flipped = mirror_in_buf_.like(x);
  std::copy(x.data, x.data + x.floats(), flipped.data);
  for (int n = 0; n < x.n; ++n) layers::flip_frame(flipped, n);
  forward_once(flipped);
  for (int n = 0; n < x.n; ++n) layers::flip_frame(masks_, n);
  for (std::size_t i = 0; i < masks_.floats(); ++i) masks_.data[i] = 0.5f * (masks_.data[i] + first.data[i]);
  for (std::size_t i = 0; i < logits_.size(); ++i) {
    logits_[i] = 0.5f * (logits_[i] + first_logits[i]);
    scores_[i] = 1.f / (1.f + std::exp(-logits_[i]));
  }
}

void MaskNet::check_input(const Act& x) const {
  if (x.c != cfg_.channels || x.h != cfg_.height() || x.w != cfg_.width())
    throw std::invalid_argument("mask net '" + cfg_.name + "': input is " + std::to_string(x.c) + "x" + std::to_string(x.h) +
                                "x" + std::to_string(x.w) + ", the config wants " + std::to_string(cfg_.channels) + "x" +
                                std::to_string(cfg_.height()) + "x" + std::to_string(cfg_.width()));
}

void MaskNet::forward_once(const Act& x) {
  check_input(x);
  const layers::Bf16Convs precision(bf16_);
  cropped_ = false;
  // mask.pool: the U-Net on the input average-pooled pool x pool, its logits resized back bilinearly
  // (pool^2 times fewer pixels; the score head reads the pooled map's top as before).
  const int pool = cfg_.mask_pool;
  Act in = x;
  if (pool > 1) {
    in = pooled_in_ = pooled_in_buf_.get(x.n, x.c, x.h / pool, x.w / pool);
    layers::avg_pool_forward(x, pool, pooled_in_);
  }
  const Act y = unet_top(in);
  if (pool > 1) {
    pooled_masks_ = pooled_masks_buf_.like(outc_.out_shape(y));
    outc_.forward(y, pooled_masks_);
    masks_ = masks_buf_.get(x.n, cfg_.n_masks, x.h, x.w);
    layers::resize_bilinear_forward(pooled_masks_, masks_);
  } else {
    masks_ = masks_buf_.like(outc_.out_shape(y));
    outc_.forward(y, masks_);
  }
  // The score head is linear up to the pooling (two 1x1 convolutions, no activation between),
  // so pooling first gives the same features on a 1x1 map: 17% of stage 1's FLOPs and its two
  // largest activations saved.
  top_gap_ = top_gap_buf_.get(y.n, y.c, 1, 1);
  layers::global_avg_pool_forward(y, top_gap_);
  score_head(x.n);
}

Act MaskNet::unet_top(const Act& in) {
  x_[0] = inc_.forward(in);
  for (int k = 0; k < kLevels; ++k) {
    pooled_[k] = pooled_buf_[k].like(pool_[k].out_shape(x_[k]));
    pool_[k].forward(x_[k], pooled_[k]);
    x_[k + 1] = down_[k]->forward(pooled_[k]);
  }
  Act y = x_[kLevels];
  for (int k = 0; k < kLevels; ++k) {
    const Act& skip = x_[kLevels - 1 - k];
    upt_[k] = upt_buf_[k].like(up_[k]->out_shape(y));
    up_[k]->forward(y, upt_[k]);
    const int dy = skip.h - upt_[k].h, dx = skip.w - upt_[k].w;
    if (dy < 0 || dx < 0) throw std::logic_error("mask net: up-sampled map larger than its skip");
    pad_top_[k] = dy / 2;
    pad_left_[k] = dx / 2;
    padded_[k] = Act{nullptr, upt_[k].n, upt_[k].c, skip.h, skip.w};
    if (layers::grad_enabled()) {  // backward reads the concatenation
      cat_[k] = cat_buf_[k].get(skip.n, skip.c + upt_[k].c, skip.h, skip.w);
      layers::concat_padded(skip, upt_[k], pad_top_[k], pad_left_[k], cat_[k]);
      y = upo_[k] = up_conv_[k]->forward(cat_[k]);
    } else {  // inference: no copy where the convolution reads the two in place
      cat_[k] = Act{nullptr, skip.n, skip.c + upt_[k].c, skip.h, skip.w};
      y = upo_[k] = up_conv_[k]->forward_cat(skip, upt_[k], pad_top_[k], pad_left_[k]);
    }
  }
  return y;
}

void MaskNet::score_head(int n_images) {
  s1_ = s1_buf_.like(score1_.out_shape(top_gap_));
  score1_.forward(top_gap_, s1_);
  gap_ = gap_buf_.like(score2_.out_shape(s1_));
  score2_.forward(s1_, gap_);
  // gap_ is n x cb x 16 floats with zero padding: exactly fc's input when 8 w0 % 16 == 0;
  // otherwise gather the real channels.
  const int F = 8 * w_[0];
  std::vector<float> feat(std::size_t(n_images) * F);
  for (int n = 0; n < n_images; ++n)
    for (int c = 0; c < F; ++c) feat[std::size_t(n) * F + c] = gap_.data[(std::size_t(n) * gap_.cb() + c / 16) * 16 + c % 16];
  logits_.resize(std::size_t(n_images) * cfg_.n_masks);
  fc_.forward(feat.data(), n_images, logits_.data());
  scores_.resize(logits_.size());
  for (std::size_t i = 0; i < logits_.size(); ++i) scores_[i] = 1.f / (1.f + std::exp(-logits_[i]));
}

void MaskNet::backward(const Act& x, const Act& dmasks, const float* dscores) {
  if (cropped_) throw std::logic_error("mask net: backward after forward_cropped (inference only)");
  const Act& top = upo_[kLevels - 1];
  const Act dtop = d_top_.like(top);
  zero(dtop);
  if (dmasks.data && cfg_.mask_pool > 1) {
    const Act d = d_pooled_masks_.like(pooled_masks_);
    layers::resize_bilinear_backward(dmasks, d);
    outc_.backward(top, d, &dtop);
  } else if (dmasks.data) {
    outc_.backward(top, dmasks, &dtop);
  }
  if (dscores) {
    const int F = 8 * w_[0];
    std::vector<float> dlogit(logits_.size()), feat(std::size_t(x.n) * F), dfeat(feat.size());
    for (std::size_t i = 0; i < logits_.size(); ++i) dlogit[i] = dscores[i] * scores_[i] * (1.f - scores_[i]);
    for (int n = 0; n < x.n; ++n)
      for (int c = 0; c < F; ++c) feat[std::size_t(n) * F + c] = gap_.data[(std::size_t(n) * gap_.cb() + c / 16) * 16 + c % 16];
    fc_.backward(feat.data(), dlogit.data(), x.n, dfeat.data());
    const Act dgap = d_gap_.like(gap_);
    zero(dgap);
    for (int n = 0; n < x.n; ++n)
      for (int c = 0; c < F; ++c) dgap.data[(std::size_t(n) * gap_.cb() + c / 16) * 16 + c % 16] = dfeat[std::size_t(n) * F + c];
    const Act ds1 = d_s1_.like(s1_);
    score2_.backward(s1_, dgap, &ds1);
    const Act dtop_gap = d_top_gap_.like(top_gap_);
    score1_.backward(top_gap_, ds1, &dtop_gap);
    const Act dtop_score = d_top_score_.like(top);
    layers::global_avg_pool_backward(dtop_gap, dtop_score);
    layers::accumulate(dtop_score, dtop);
  }
  // Up path in reverse. Level k's input is x_4 (k = 0) or the previous up's output.
  Act g = dtop;
  int ping = 0;
  for (int k = kLevels - 1; k >= 0; --k) {
    const int level = kLevels - 1 - k;  // the skip's
    const Act dcat = d_cat_.like(cat_[k]);
    up_conv_[k]->backward(cat_[k], g, dcat);
    const Act dsk = d_skip_[level].like(x_[level]), dpad = d_padded_.like(padded_[k]);
    layers::split_channels(dcat, dsk, dpad);
    const Act dupt = d_upt_.like(upt_[k]);
    crop_from(dpad, dupt, pad_top_[k], pad_left_[k]);
    const Act& input = k == 0 ? x_[kLevels] : upo_[k - 1];
    const Act din = d_level_[ping ^= 1].like(input);
    up_[k]->backward(input, dupt, &din);
    g = din;
  }
  // Down path: x_{k+1} = down_k(pool(x_k)); each level also gets its skip's gradient.
  for (int k = kLevels - 1; k >= 0; --k) {
    const Act dpool = d_pooled_.like(pooled_[k]);
    down_[k]->backward(pooled_[k], g, dpool);
    const Act dxk = d_level_[ping ^= 1].like(x_[k]);
    pool_[k].backward(x_[k], dpool, dxk);
    layers::accumulate(d_skip_[k].like(x_[k]), dxk);
    g = dxk;
  }
  inc_.backward(cfg_.mask_pool > 1 ? pooled_in_ : x, g, Act{});  // the TORE input needs no gradient
}

}  // namespace yelan
