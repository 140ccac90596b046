// MaskNet::forward_cropped: stage 1 over a box of the frame, the rest of every map the empty
// room's (mask_net.h says why and what it costs).
#include <algorithm>
#include <cstring>
#include <stdexcept>

#include "engine/mask_net.h"
#include "layers/simple.h"

namespace yelan {

using layers::Act;
using Box = MaskNet::Box;

namespace {

Box grow(const Box& b, int g, const Act& in) { return Box{b.x0 - g, b.y0 - g, b.x1 + g, b.y1 + g}.clipped(in.w, in.h); }

// `src` inside b, as a map of its own.
Act window(const Act& src, const Box& b, layers::ActBuf& buf) {
  const Act w = buf.get(1, src.c, b.height(), b.width());
  layers::copy_window(src, b.y0, b.x0, w, 0, 0, b.height(), b.width());
  return w;
}

// The part `part` of a window whose top-left is at `origin` of the frame, written into dst.
void put(const Act& win, const Box& origin, const Box& part, const Act& dst) {
  layers::copy_window(win, part.y0 - origin.y0, part.x0 - origin.x0, dst, part.y0, part.x0, part.height(), part.width());
}

// Undoes the last run's writes: dst inside b back to the zero frame's.
void restore(const Act& zero_frame, const Act& dst, Box& b) {
  if (!b.empty()) layers::copy_window(zero_frame, b.y0, b.x0, dst, b.y0, b.x0, b.height(), b.width());
  b = {};
}

void keep(const Act& a, layers::ActBuf& z, layers::ActBuf& c) {
  for (layers::ActBuf* buf : {&z, &c}) std::memcpy(buf->like(a).data, a.data, a.floats() * sizeof(float));
}

}  // namespace

void MaskNet::prepare_zero_frame(int channels) {
  const Act z = win_a_.get(1, channels, cfg_.height(), cfg_.width());
  std::memset(z.data, 0, z.floats() * sizeof(float));
  const Act top = unet_top(z);
  for (int k = 0; k <= kLevels; ++k) keep(x_[k], zx_[k], cx_[k]);
  for (int k = 0; k < kLevels; ++k) {
    for (layers::ActBuf* buf : {&zpad_[k], &cpad_[k]}) {  // F.pad of the up-sampled map
      const Act p = buf->like(padded_[k]);
      std::memset(p.data, 0, p.floats() * sizeof(float));
      layers::copy_window(upt_[k], 0, 0, p, pad_top_[k], pad_left_[k], upt_[k].h, upt_[k].w);
    }
    keep(upo_[k], zup_[k], cup_[k]);
  }
  const Act m = win_out_.like(outc_.out_shape(top));
  outc_.forward(top, m);
  keep(m, zmask_, cmask_);
  const Act g = gap_win_.get(1, top.c, 1, 1);
  layers::global_avg_pool_forward(top, g);
  zero_top_sum_.assign(g.data, g.data + g.floats());
  for (float& v : zero_top_sum_) v *= float(top.h) * float(top.w);
  written_x_.fill({});
  written_pad_.fill({});
  written_up_.fill({});
  written_mask_ = {};
  have_zero_ = true;
  zero_bf16_ = layers::bf16_active();
}

Box MaskNet::forward_cropped(const Act& x, Box box) {
  check_input(x);
  if (layers::grad_enabled() || x.n != 1) throw std::logic_error("mask net: forward_cropped is for inference on one frame (NoGrad)");
  const layers::Bf16Convs precision(bf16_);
  const int H = x.h, W = x.w, a = 1 << kLevels;
  box = Box{box.x0 / a * a, box.y0 / a * a, (box.x1 + a - 1) / a * a, (box.y1 + a - 1) / a * a}.clipped(W, H);
  if (box.empty() || cfg_.mask_pool > 1 || (box.x0 == 0 && box.y0 == 0 && box.x1 == W && box.y1 == H)) {
    forward(x);
    return {0, 0, W, H};
  }
  if (!have_zero_ || zero_bf16_ != layers::bf16_active()) prepare_zero_frame(x.c);
  // Each level's box: the input box's cells there, grown by the halo.
  std::array<Box, kLevels + 1> r;
  for (int k = 0; k <= kLevels; ++k) {
    const int s = 1 << k;
    r[k] = Box{box.x0 / s - kCropHalo, box.y0 / s - kCropHalo, (box.x1 + s - 1) / s + kCropHalo, (box.y1 + s - 1) / s + kCropHalo}
               .clipped(zx_[k].act.w, zx_[k].act.h);
  }
  // inc, then down: each double convolution reads its box grown by 2 (two 3x3 layers) and
  // keeps the box, where the window's own zero padding cannot reach.
  {
    restore(zx_[0].act, cx_[0].act, written_x_[0]);
    const Box in = grow(r[0], 2, x);
    put(inc_.forward(window(x, in, win_a_)), in, r[0], cx_[0].act);
    written_x_[0] = r[0];
  }
  for (int k = 0; k < kLevels; ++k) {
    restore(zx_[k + 1].act, cx_[k + 1].act, written_x_[k + 1]);
    const Box in = grow(r[k + 1], 2, zx_[k + 1].act);
    const Act src = window(cx_[k].act, {2 * in.x0, 2 * in.y0, 2 * in.x1, 2 * in.y1}, win_a_);
    const Act pooled = win_b_.like(pool_[k].out_shape(src));
    pool_[k].forward(src, pooled);
    put(down_[k]->forward(pooled), in, r[k + 1], cx_[k + 1].act);
    written_x_[k + 1] = r[k + 1];
  }
  // Up: the upsample over the cells under the level's box grown by 2, into the padded map
  // (the zero frame's elsewhere), then the double convolution over the box.
  for (int k = 0; k < kLevels; ++k) {
    const int level = kLevels - 1 - k;
    const Act& below = k == 0 ? cx_[kLevels].act : cup_[k - 1].act;
    const Act& skip = cx_[level].act;
    restore(zpad_[k].act, cpad_[k].act, written_pad_[k]);
    restore(zup_[k].act, cup_[k].act, written_up_[k]);
    const Box in = grow(r[level], 2, skip);
    const Box cells = Box{in.x0 / 2, in.y0 / 2, (in.x1 + 1) / 2, (in.y1 + 1) / 2}.clipped(below.w, below.h);
    const Act tin = window(below, cells, win_a_);
    const Act t = win_out_.like(up_[k]->out_shape(tin));
    up_[k]->forward(tin, t);
    const Box up_box{2 * cells.x0 + pad_left_[k], 2 * cells.y0 + pad_top_[k], 2 * cells.x1 + pad_left_[k], 2 * cells.y1 + pad_top_[k]};
    put(t, up_box, up_box, cpad_[k].act);
    written_pad_[k] = up_box;
    const Act sa = window(skip, in, win_a_), sb = window(cpad_[k].act, in, win_b_);
    put(up_conv_[k]->forward_cat(sa, sb, 0, 0), in, r[level], cup_[k].act);
    written_up_[k] = r[level];
  }
  // The masks over the input's box, the zero frame's elsewhere; the score head on the frame's
  // mean: the zero frame's sum with the box's part exchanged for the run's.
  const Box& r0 = r[0];
  const Act top = window(cup_[kLevels - 1].act, r0, win_a_);
  const Act m = win_out_.like(outc_.out_shape(top));
  outc_.forward(top, m);
  restore(zmask_.act, cmask_.act, written_mask_);
  put(m, r0, r0, cmask_.act);
  written_mask_ = r0;
  masks_ = cmask_.act;
  top_gap_ = top_gap_buf_.get(1, top.c, 1, 1);
  layers::global_avg_pool_forward(top, top_gap_);
  const Act zero_gap = gap_win_.get(1, top.c, 1, 1);
  layers::global_avg_pool_forward(window(zup_[kLevels - 1].act, r0, win_b_), zero_gap);
  const float area = float(r0.height()) * float(r0.width()), frame = float(H) * float(W);
  for (std::size_t i = 0; i < top_gap_.floats(); ++i)
    top_gap_.data[i] = (zero_top_sum_[i] + area * (top_gap_.data[i] - zero_gap.data[i])) / frame;
  score_head(1);
  if (cfg_.mask_mirror) add_mirror(x);
  cropped_ = true;
  return box;
}

}  // namespace yelan
