#include "engine/pose_net.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>

namespace yelan {

using layers::Act;

namespace {
int conv_out(int n, int k, int s, int p) { return (n + 2 * p - k) / s + 1; }

void zero(const Act& a) { std::memset(a.data, 0, a.floats() * sizeof(float)); }
}  // namespace

PoseNet::PoseNet(const ModelConfig& cfg)
    : cfg_(cfg),
      mid_h_(conv_out(conv_out(conv_out(cfg.height(), 7, 2, 3), 3, 2, 1), 3, 2, 1)),
      mid_w_(conv_out(conv_out(conv_out(cfg.width(), 7, 2, 3), 3, 2, 1), 3, 2, 1)),
      conv1_({cfg.channels, cfg.resnet_c64(), 7, 2, 3}),
      bn1_(cfg.resnet_c64(), true),
      pool_(3, 2, 1),
      cl_(cfg.resnet_mid(), cfg.hidden, cfg.bidirectional),
      skip_(cfg.resnet_mid() + (cfg.convlstm ? cfg.hidden : 0), cfg.resnet_mid(), layers::ResidualKind::regular) {
  if (cfg.stages > 8) throw ConfigError(cfg.name + ": at most 8 hourglass stages");
  const int c64 = cfg.resnet_c64(), mid = cfg.resnet_mid();
  for (int i = 0; i < 3; ++i) resnet_.push_back(std::make_unique<layers::BasicBlock>(c64, c64, 1));
  resnet_.push_back(std::make_unique<layers::BasicBlock>(c64, mid, 2));
  for (int i = 0; i < 3; ++i) resnet_.push_back(std::make_unique<layers::BasicBlock>(mid, mid, 1));
  for (int t = 0; t < cfg.stages; ++t) {
    if (t > 0)
      combiners_.push_back(std::make_unique<layers::ResidualBlock>(3 * cfg.joints, mid, layers::ResidualKind::regular));
    std::array<std::unique_ptr<layers::HourglassStage>, 3> planes;
    for (auto& p : planes)
      p = std::make_unique<layers::HourglassStage>(mid, cfg.joints, cfg.hourglass_lo(), cfg.hourglass_hi(), mid_h_, mid_w_);
    hourglass_.push_back(std::move(planes));
  }
}

void PoseNet::params(layers::ParamList& out) {
  conv1_.params("in_cnn.0.", out);
  bn1_.params("in_cnn.1.", out);
  for (int i = 0; i < 7; ++i)
    resnet_[i]->params(i < 3 ? "in_cnn.4." + std::to_string(i) + "." : "in_cnn.5." + std::to_string(i - 3) + ".", out);
  if (cfg_.convlstm) cl_.params("cl.", out);
  skip_.params("cl_skip_block.", out);
  static const char* plane_names[3] = {"xy_hm_cnns.", "zy_hm_cnns.", "xz_hm_cnns."};
  for (int p = 0; p < 3; ++p)
    for (int t = 0; t < cfg_.stages; ++t) hourglass_[t][p]->params(plane_names[p] + std::to_string(t) + ".", out);
  for (std::size_t t = 0; t < combiners_.size(); ++t)
    combiners_[t]->params("hm_combiners." + std::to_string(t) + ".combine_block.", out);
}

void PoseNet::init(std::uint64_t seed) {
  conv1_.init(seed * 1000 + 1);
  for (std::size_t i = 0; i < resnet_.size(); ++i) resnet_[i]->init(seed * 1000 + 10 + i);
  cl_.init(seed * 1000 + 20);
  skip_.init(seed * 1000 + 21);
  for (int t = 0; t < cfg_.stages; ++t)
    for (int p = 0; p < 3; ++p) hourglass_[t][p]->init(seed * 1000 + 100 + 3 * t + p);
  for (std::size_t t = 0; t < combiners_.size(); ++t) combiners_[t]->init(seed * 1000 + 200 + t);
}

void PoseNet::set_training(bool on) {
  bn1_.training = on;
  for (auto& b : resnet_) b->set_training(on);
  skip_.set_training(on);
  for (auto& st : hourglass_)
    for (auto& p : st) p->set_training(on);
  for (auto& c : combiners_) c->set_training(on);
}

void PoseNet::weights_changed() {
  have_zero_feat_ = false;
  conv1_.weights_changed();
  for (auto& b : resnet_) b->weights_changed();
  cl_.weights_changed();
  skip_.weights_changed();
  for (auto& st : hourglass_)
    for (auto& p : st) p->weights_changed();
  for (auto& c : combiners_) c->weights_changed();
}

void PoseNet::check_input(const Act& x) const {
  if (x.c != cfg_.channels || x.h != cfg_.height() || x.w != cfg_.width())
    throw std::invalid_argument("pose net '" + cfg_.name + "': input is " + std::to_string(x.c) + "x" + std::to_string(x.h) +
                                "x" + std::to_string(x.w) + ", the config wants " + std::to_string(cfg_.channels) + "x" +
                                std::to_string(cfg_.height()) + "x" + std::to_string(cfg_.width()));
}

Act PoseNet::head_forward(const Act& x) {
  c1_ = c1_buf_.like(conv1_.out_shape(x));
  conv1_.forward(x, c1_);
  b1_ = b1_buf_.like(c1_);
  bn1_.forward(c1_, b1_);
  pooled_ = p_buf_.like(pool_.out_shape(b1_));
  pool_.forward(b1_, pooled_);
  res_in_.assign(1, pooled_);
  for (auto& b : resnet_) res_in_.push_back(b->forward(res_in_.back()));
  return res_in_.back();
}

void PoseNet::forward(const Act& x, int S) {
  check_input(x);
  S_ = S;
  cropped_ = false;
  feats_ = head_forward(x);
  tail_forward(feats_, x.n);
}

PoseNet::CropBox PoseNet::forward_cropped(const Act& x, CropBox box, int S) {
  check_input(x);
  if (bn1_.training) throw std::logic_error("pose net: forward_cropped is for inference (set_training(false))");
  S_ = S;
  const int H = x.h, W = x.w, F = cfg_.resnet_mid();
  if (!have_zero_feat_) {
    Act zero_in = crop_buf_.get(1, x.c, H, W);
    zero(zero_in);
    const Act z = head_forward(zero_in);
    const Act keep = zero_feat_buf_.like(z);
    std::memcpy(keep.data, z.data, z.floats() * sizeof(float));
    have_zero_feat_ = true;
  }
  const Act z0 = zero_feat_buf_.get(1, F, mid_h_, mid_w_);
  feats_ = full_feat_buf_.get(x.n, F, mid_h_, mid_w_);
  for (int n = 0; n < x.n; ++n) std::memcpy(feats_.data + n * z0.floats(), z0.data, z0.floats() * sizeof(float));
  box.x0 = std::max(0, box.x0) / 8 * 8;
  box.y0 = std::max(0, box.y0) / 8 * 8;
  box.x1 = std::min(W, (box.x1 + 7) / 8 * 8);
  box.y1 = std::min(H, (box.y1 + 7) / 8 * 8);
  if (!box.empty()) {
    const int ch = box.y1 - box.y0, cw = box.x1 - box.x0;
    const Act in = crop_buf_.get(x.n, x.c, ch, cw);
    layers::copy_window(x, box.y0, box.x0, in, 0, 0, ch, cw);
    const Act f = head_forward(in);
    // the crop's feature pixel (i, j) is the frame's (y0/8 + i, x0/8 + j)
    const int oy = box.y0 / 8, ox = box.x0 / 8, fh = std::min(f.h, mid_h_ - oy), fw = std::min(f.w, mid_w_ - ox);
    layers::copy_window(f, 0, 0, feats_, oy, ox, fh, fw);
  }
  cropped_ = true;
  tail_forward(feats_, x.n);
  return box.empty() ? CropBox{} : box;
}

void PoseNet::tail_forward(const Act& feats, int n_images) {
  if (cfg_.convlstm) {
    cl_out_ = cl_.forward(feats, S_);
    cat_ = cat_buf_.get(feats.n, feats.c + cl_out_.c, feats.h, feats.w);
    layers::concat_channels(feats, cl_out_, cat_);
  } else {
    cat_ = feats;
  }
  const Act skip_out = skip_.forward(cat_);
  const int T = cfg_.stages, J = cfg_.joints;
  inp_.assign(T, Act{});
  hmcat_.assign(T, Act{});
  logits_.assign(T, {});
  probs_.assign(T, {});
  for (int t = 0; t < T; ++t) {
    if (t == 0) {
      inp_[0] = skip_out;
    } else {
      // stage t sees the previous input plus a block over the previous stage's heatmaps
      const Act hc = hmcat_[t - 1] = hmcat_buf_[t - 1].get(skip_out.n, 3 * J, skip_out.h, skip_out.w);
      Act tmp = g_cat_.get(skip_out.n, 2 * J, skip_out.h, skip_out.w);
      layers::concat_channels(probs_[t - 1][0], probs_[t - 1][1], tmp);
      layers::concat_channels(tmp, probs_[t - 1][2], hc);
      const Act comb = combiners_[t - 1]->forward(hc);
      inp_[t] = inp_buf_[t].like(skip_out);
      layers::add_forward(inp_[t - 1], comb, inp_[t]);
    }
    for (int p = 0; p < 3; ++p) {
      logits_[t][p] = hourglass_[t][p]->forward(inp_[t]);
      probs_[t][p] = prob_buf_[t][p].like(logits_[t][p]);
      layers::flat_softmax_forward(logits_[t][p], probs_[t][p]);
    }
  }
  joints_.resize(std::size_t(n_images) * J * 3);
  layers::dsnt_joints_forward(probs_[T - 1][0], probs_[T - 1][1], probs_[T - 1][2], joints_.data());
}

void PoseNet::backward(const Act& x, const std::vector<std::array<Act, 3>>& dheat, const float* djoints) {
  if (cropped_) throw std::logic_error("pose net: backward after forward_cropped (inference only)");
  const int T = cfg_.stages, J = cfg_.joints;
  const Act shape = inp_[0];
  const Act dI = g_inp_.like(shape);
  zero(dI);
  std::array<Act, 3> extra[8];
  for (int t = 0; t < T; ++t)
    for (int p = 0; p < 3; ++p) extra[t][p] = Act{};
  for (int t = T - 1; t >= 0; --t) {
    std::array<Act, 3> dprob;
    for (int p = 0; p < 3; ++p) {
      dprob[p] = g_extra_[t][p].like(probs_[t][p]);
      if (extra[t][p].data) {
        if (extra[t][p].data != dprob[p].data) std::memcpy(dprob[p].data, extra[t][p].data, dprob[p].floats() * sizeof(float));
      }
      else zero(dprob[p]);
      if (t < int(dheat.size()) && dheat[t][p].data) layers::accumulate(dheat[t][p], dprob[p]);
    }
    if (t == T - 1 && djoints) {
      const Act a = g_prob_.like(probs_[t][0]), b = g_logit_.like(probs_[t][1]), c = g_hg_.like(probs_[t][2]);
      layers::dsnt_joints_backward(djoints, a, b, c);
      layers::accumulate(a, dprob[0]);
      layers::accumulate(b, dprob[1]);
      layers::accumulate(c, dprob[2]);
    }
    for (int p = 0; p < 3; ++p) {
      const Act dlogit = g_logit_.like(logits_[t][p]);
      layers::flat_softmax_backward(probs_[t][p], dprob[p], dlogit);
      const Act dh = g_hg_.like(shape);
      hourglass_[t][p]->backward(inp_[t], dlogit, dh);
      layers::accumulate(dh, dI);
    }
    if (t > 0) {  // inp_t = inp_{t-1} + combiner(cat heatmaps_{t-1}): dI flows on unchanged
      const Act dhc = g_cat_.like(hmcat_[t - 1]);
      combiners_[t - 1]->backward(hmcat_[t - 1], dI, dhc);
      Act d01 = g_prob_.get(shape.n, 2 * J, shape.h, shape.w);
      for (int p = 0; p < 3; ++p) extra[t - 1][p] = g_extra_[t - 1][p].like(probs_[t - 1][p]);
      layers::split_channels(dhc, d01, extra[t - 1][2]);
      layers::split_channels(d01, extra[t - 1][0], extra[t - 1][1]);
    }
  }
  // skip block over cat[feats, convlstm(feats)]
  const Act dcat = g_cat_.like(cat_);
  skip_.backward(cat_, dI, dcat);
  Act g = dcat;
  if (cfg_.convlstm) {
    const Act dfeat = g_feat_a_.like(feats_), dcl = g_cl_.like(cl_out_);
    layers::split_channels(dcat, dfeat, dcl);
    const Act dfeat_cl = g_feat_b_.like(feats_);
    cl_.backward(feats_, dcl, dfeat_cl);
    layers::accumulate(dfeat_cl, dfeat);
    g = dfeat;
  }
  for (int i = int(resnet_.size()) - 1; i >= 0; --i) {
    const Act d = (i % 2 ? g_feat_b_ : g_feat_a_).like(res_in_[i]);
    resnet_[i]->backward(res_in_[i], g, d);
    g = d;
  }
  const Act db1 = g_b1_.like(b1_);
  pool_.backward(b1_, g, db1);
  const Act dc1 = g_c1_.like(c1_);
  bn1_.backward(c1_, b1_, db1, dc1);
  conv1_.backward(x, dc1, nullptr);
}

}  // namespace yelan
