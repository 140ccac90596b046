#include "engine/pose_net.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>

namespace yelan {

using layers::Act;

namespace {
int conv_out(int n, int k, int s, int p) { return (n + 2 * p - k) / s + 1; }
// conv1 and the max-pool stride 4 between them; layer2's first block makes it 8, or not.
int layer2_stride(const ModelConfig& cfg) { return cfg.head_stride / 4; }

void zero(const Act& a) { std::memset(a.data, 0, a.floats() * sizeof(float)); }
}  // namespace

PoseNet::PoseNet(const ModelConfig& cfg)
    : cfg_(cfg),
      mid_h_(conv_out(conv_out(conv_out(cfg.height(), 7, 2, 3), 3, 2, 1), 3, layer2_stride(cfg), 1)),
      mid_w_(conv_out(conv_out(conv_out(cfg.width(), 7, 2, 3), 3, 2, 1), 3, layer2_stride(cfg), 1)),
      conv1_({cfg.pose_channels(), cfg.resnet_c64(), 7, 2, 3}),
      bn1_(cfg.resnet_c64(), true),
      pool_(3, 2, 1),
      cl_(cfg.resnet_mid(), cfg.hidden, cfg.bidirectional),
      skip_(cfg.resnet_mid() + (cfg.convlstm ? cfg.hidden : 0), cfg.resnet_mid(), layers::ResidualKind::regular) {
  const int c64 = cfg.resnet_c64(), mid = cfg.resnet_mid();
  for (int i = 0; i < 3; ++i) resnet_.push_back(std::make_unique<layers::BasicBlock>(c64, c64, 1));
  resnet_.push_back(std::make_unique<layers::BasicBlock>(c64, mid, layer2_stride(cfg)));
  for (int i = 0; i < 3; ++i) resnet_.push_back(std::make_unique<layers::BasicBlock>(mid, mid, 1));
  stages_.resize(std::size_t(cfg.stages));
  for (int t = 0; t < cfg.stages; ++t) {
    if (t > 0) stages_[t].combiner = std::make_unique<layers::ResidualBlock>(3 * cfg.joints, mid, layers::ResidualKind::regular);
    for (auto& p : stages_[t].planes)
      p = std::make_unique<layers::HourglassStage>(mid, cfg.joints, cfg.hourglass_lo(), cfg.hourglass_hi(), mid_h_, mid_w_,
                                                   cfg.hourglass_skip);
    if (cfg.depth_map)
      stages_[t].depth = std::make_unique<layers::HourglassStage>(mid, cfg.joints, cfg.hourglass_lo(), cfg.hourglass_hi(), mid_h_,
                                                                  mid_w_, cfg.hourglass_skip);
  }
}

void PoseNet::check_input(const Act& x) const {
  if (x.c != cfg_.pose_channels() || x.h != cfg_.height() || x.w != cfg_.width())
    throw std::invalid_argument("pose net '" + cfg_.name + "': input is " + std::to_string(x.c) + "x" + std::to_string(x.h) +
                                "x" + std::to_string(x.w) + ", the config wants " + std::to_string(cfg_.pose_channels()) + "x" +
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
  if (!have_zero_feat_ || zero_feat_bf16_ != layers::bf16_active()) {  // the empty frame's, in this run's precision
    Act zero_in = crop_buf_.get(1, x.c, H, W);
    zero(zero_in);
    const Act z = head_forward(zero_in);
    const Act keep = zero_feat_buf_.like(z);
    std::memcpy(keep.data, z.data, z.floats() * sizeof(float));
    have_zero_feat_ = true;
    zero_feat_bf16_ = layers::bf16_active();
  }
  const Act z0 = zero_feat_buf_.get(1, F, mid_h_, mid_w_);
  feats_ = full_feat_buf_.get(x.n, F, mid_h_, mid_w_);
  for (int n = 0; n < x.n; ++n) std::memcpy(feats_.data + n * z0.floats(), z0.data, z0.floats() * sizeof(float));
  const int s = cfg_.head_stride;
  box.x0 = std::max(0, box.x0) / s * s;
  box.y0 = std::max(0, box.y0) / s * s;
  box.x1 = std::min(W, (box.x1 + s - 1) / s * s);
  box.y1 = std::min(H, (box.y1 + s - 1) / s * s);
  if (!box.empty()) {
    const int ch = box.height(), cw = box.width();
    const Act in = crop_buf_.get(x.n, x.c, ch, cw);
    layers::copy_window(x, box.y0, box.x0, in, 0, 0, ch, cw);
    const Act f = head_forward(in);
    // the crop's feature pixel (i, j) is the frame's (y0/s + i, x0/s + j)
    const int oy = box.y0 / s, ox = box.x0 / s, fh = std::min(f.h, mid_h_ - oy), fw = std::min(f.w, mid_w_ - ox);
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
  for (int t = 0; t < T; ++t) {
    Stage& st = stages_[t];
    if (t == 0) {
      st.inp = skip_out;
    } else {
      // stage t sees the previous input plus a block over the previous stage's heatmaps
      const Stage& prev = stages_[t - 1];
      st.hmcat = st.hmcat_buf.get(skip_out.n, 3 * J, skip_out.h, skip_out.w);
      const Act pair = heat_pair_.get(skip_out.n, 2 * J, skip_out.h, skip_out.w);
      layers::concat_channels(prev.probs[0], prev.probs[1], pair);
      layers::concat_channels(pair, prev.probs[2], st.hmcat);
      const Act comb = st.combiner->forward(st.hmcat);
      st.inp = st.inp_buf.like(skip_out);
      layers::add_forward(prev.inp, comb, st.inp);
    }
    for (int p = 0; p < 3; ++p) {
      st.logits[p] = st.planes[p]->forward(st.inp);
      st.probs[p] = st.prob_buf[p].like(st.logits[p]);
      layers::flat_softmax_forward(st.logits[p], st.probs[p]);
    }
    if (st.depth) st.depth_out = st.depth->forward(st.inp);
  }
  joints_.resize(std::size_t(n_images) * J * 3);
  stage_joints(T - 1, joints_.data());
}

void PoseNet::stage_joints(int t, float* out) const {
  const Stage& st = stages_[std::size_t(t)];
  layers::stage_joints_forward(st.probs[0], st.probs[1], st.probs[2], st.depth ? &st.depth_out : nullptr, out);
}

void PoseNet::backward(const Act& x, const std::vector<StageGrads>& dheat, const float* djoints) {
  if (cropped_) throw std::logic_error("pose net: backward after forward_cropped (inference only)");
  const int T = cfg_.stages, J = cfg_.joints;
  const Act shape = stages_[0].inp;
  const Act dI = d_inp_.like(shape);
  zero(dI);
  for (int t = T - 1; t >= 0; --t) {
    Stage& st = stages_[t];
    // dL/d this stage's heatmaps: what stage t+1's combiner sent back (already in dprob_buf,
    // written by the split below), or zero for the last stage; plus any direct loss
    std::array<Act, 3> dprob;
    for (int p = 0; p < 3; ++p) {
      dprob[p] = st.dprob_buf[p].like(st.probs[p]);
      if (t == T - 1) zero(dprob[p]);
      if (t < int(dheat.size()) && dheat[t][p].data) layers::accumulate(dheat[t][p], dprob[p]);
    }
    Act ddepth;
    if (st.depth) {
      ddepth = st.ddepth_buf.like(st.depth_out);
      zero(ddepth);
      if (t < int(dheat.size()) && dheat[t][3].data) layers::accumulate(dheat[t][3], ddepth);
    }
    if (t == T - 1 && djoints) {
      std::array<Act, 3> dj;
      for (int p = 0; p < 3; ++p) dj[p] = d_dsnt_[p].like(st.probs[p]);
      const Act dd = st.depth ? d_depth_joints_.like(st.depth_out) : Act{};
      layers::stage_joints_backward(djoints, st.probs[0], st.depth ? &st.depth_out : nullptr, dj[0], dj[1], dj[2], &dd);
      for (int p = 0; p < 3; ++p) layers::accumulate(dj[p], dprob[p]);
      if (st.depth) layers::accumulate(dd, ddepth);
    }
    for (int p = 0; p < 3; ++p) {
      const Act dlogit = d_logits_.like(st.logits[p]);
      layers::flat_softmax_backward(st.probs[p], dprob[p], dlogit);
      const Act dh = d_hg_in_.like(shape);
      st.planes[p]->backward(st.inp, dlogit, dh);
      layers::accumulate(dh, dI);
    }
    if (st.depth) {
      const Act dh = d_hg_in_.like(shape);
      st.depth->backward(st.inp, ddepth, dh);
      layers::accumulate(dh, dI);
    }
    if (t > 0) {  // inp_t = inp_{t-1} + combiner(cat heatmaps_{t-1}): dI flows on unchanged
      Stage& prev = stages_[t - 1];
      const Act dhc = d_hmcat_.like(st.hmcat);
      st.combiner->backward(st.hmcat, dI, dhc);
      const Act dpair = heat_pair_.get(shape.n, 2 * J, shape.h, shape.w);
      std::array<Act, 3> dprev;
      for (int p = 0; p < 3; ++p) dprev[p] = prev.dprob_buf[p].like(prev.probs[p]);
      layers::split_channels(dhc, dpair, dprev[2]);
      layers::split_channels(dpair, dprev[0], dprev[1]);
    }
  }
  // skip block over cat[feats, convlstm(feats)]
  const Act dcat = d_cat_.like(cat_);
  skip_.backward(cat_, dI, dcat);
  Act g = dcat;
  if (cfg_.convlstm) {
    const Act dfeat = d_feat_a_.like(feats_), dcl = d_cl_out_.like(cl_out_);
    layers::split_channels(dcat, dfeat, dcl);
    const Act dfeat_cl = d_feat_b_.like(feats_);
    cl_.backward(feats_, dcl, dfeat_cl);
    layers::accumulate(dfeat_cl, dfeat);
    g = dfeat;
  }
  for (int i = int(resnet_.size()) - 1; i >= 0; --i) {
    const Act d = (i % 2 ? d_feat_b_ : d_feat_a_).like(res_in_[i]);
    resnet_[i]->backward(res_in_[i], g, d);
    g = d;
  }
  const Act db1 = d_b1_.like(b1_);
  pool_.backward(b1_, g, db1);
  const Act dc1 = d_c1_.like(c1_);
  bn1_.backward(c1_, b1_, db1, dc1);
  conv1_.backward(x, dc1, nullptr);
}

}  // namespace yelan
