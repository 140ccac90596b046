#include "layers/convlstm.h"

#include <algorithm>

#include <cstring>
#include <stdexcept>

#include "kernels/lstm.h"
#include "layers/simple.h"

namespace yelan::layers {
namespace {

// Conv output (4H channels, i f o g) <-> the LSTM kernel's layout: gate k in its own
// ceil(H/16) blocks. When H is a multiple of 16 the two coincide.
void group_gates(const Act& g, int hidden, const Act& grouped, bool to_grouped) {
  const int hb = (hidden + 15) / 16;
  for (int n = 0; n < g.n; ++n)
    for (int k = 0; k < 4; ++k) {
      Act view{grouped.data, grouped.n, 4 * hb * 16, grouped.h, grouped.w};
      if (to_grouped) copy_channels(g, n, k * hidden, view, n, k * hb * 16, hidden);
      else copy_channels(view, n, k * hb * 16, g, n, k * hidden, hidden);
    }
}

}  // namespace

WindowConvLSTM::WindowConvLSTM(int in, int hidden, bool bidirectional)
    : in_(in), hidden_(hidden), bidir_(bidirectional),
      cell_({in + hidden, 4 * hidden, 3, 1, 1, true}),
      fuse_({bidirectional ? 2 * hidden : hidden, hidden, 1, 1, 0, true}) {}

void WindowConvLSTM::params(const std::string& prefix, ParamList& out) {
  cell_.params(prefix + "cell_list.0.conv.", out);
  fuse_.params(prefix + "fuse_list.0.", out);
}

void WindowConvLSTM::init(std::uint64_t seed) {
  cell_.init(seed * 2 + 1);
  fuse_.init(seed * 2 + 2);
}

void WindowConvLSTM::weights_changed() {
  cell_.weights_changed();
  fuse_.weights_changed();
}

void WindowConvLSTM::run_direction(const Act& x, int dir) {
  const int hb = (hidden_ + 15) / 16;
  auto& steps = steps_[dir];
  if (streaming_ && B_ != 1) throw std::invalid_argument("convlstm: streaming runs one window at a time");
  const bool carried = streaming_ && have_state_ && carry_h_.size() == Act{nullptr, 1, hidden_, x.h, x.w}.floats();
  steps.resize(S_);
  for (int k = 0; k < S_; ++k) {
    const int t = dir == 0 ? k : S_ - 1 - k;  // processing order
    Step& st = steps[t];
    const Act cat = st.cat.get(B_, in_ + hidden_, x.h, x.w);
    for (int b = 0; b < B_; ++b) {
      copy_channels(x, b * S_ + t, 0, cat, b, 0, in_);
      if (k == 0 && carried) {
        copy_channels(Act{carry_h_.data(), 1, hidden_, x.h, x.w}, 0, 0, cat, b, in_, hidden_);
      } else if (k == 0) {
        zero_channels(cat, b, in_, hidden_);
      } else {
        const int tp = dir == 0 ? t - 1 : t + 1;
        copy_channels(steps[tp].h.get(B_, hidden_, x.h, x.w), b, 0, cat, b, in_, hidden_);
      }
    }
    const Act gates = gates_.get(B_, 4 * hidden_, x.h, x.w);
    cell_.forward(cat, gates, !grad_enabled());  // Winograd where no backward follows
    Act grouped = gates;
    if (hidden_ % 16) {
      grouped = grouped_.get(B_, 4 * hb * 16, x.h, x.w);
      group_gates(gates, hidden_, grouped, true);
    }
    const Act act = st.act.get(B_, 4 * hb * 16, x.h, x.w);
    const Act c = st.c.get(B_, hidden_, x.h, x.w), tc = st.tanh_c.get(B_, hidden_, x.h, x.w);
    const Act h = st.h.get(B_, hidden_, x.h, x.w);
    const float* c_prev = k == 0 ? (carried ? carry_c_.data() : nullptr)
                                 : steps[dir == 0 ? t - 1 : t + 1].c.get(B_, hidden_, x.h, x.w).data;
    kernels::lstm_kernels().fwd({B_, hb, x.pixels()}, grouped.data, c_prev, act.data, c.data, h.data, tc.data);
  }
  if (streaming_) {  // keep the last state for the next call
    const Act h = steps[S_ - 1].h.get(B_, hidden_, x.h, x.w), c = steps[S_ - 1].c.get(B_, hidden_, x.h, x.w);
    if (carry_h_.size() != h.floats()) carry_h_ = Floats(h.floats()), carry_c_ = Floats(c.floats());
    std::copy_n(h.data, h.floats(), carry_h_.data());
    std::copy_n(c.data, c.floats(), carry_c_.data());
    have_state_ = true;
  }
}

void WindowConvLSTM::set_streaming(bool on) {
  if (on && bidir_) throw std::invalid_argument("convlstm: streaming needs the causal (forward-only) mode");
  streaming_ = on;
  have_state_ = false;
}

Act WindowConvLSTM::forward(const Act& x, int frames_per_window) {
  if (x.c != in_ || frames_per_window < 1 || x.n % frames_per_window)
    throw std::invalid_argument("convlstm: input of " + std::to_string(x.n) + " frames x " + std::to_string(x.c) +
                                " channels is not windows of " + std::to_string(frames_per_window) + " x " +
                                std::to_string(in_));
  S_ = frames_per_window;
  B_ = x.n / S_;
  run_direction(x, 0);
  if (bidir_) run_direction(x, 1);
  const Act fin = fuse_in_.get(x.n, bidir_ ? 2 * hidden_ : hidden_, x.h, x.w);
  for (int b = 0; b < B_; ++b)
    for (int t = 0; t < S_; ++t) {
      copy_channels(steps_[0][t].h.get(B_, hidden_, x.h, x.w), b, 0, fin, b * S_ + t, 0, hidden_);
      if (bidir_) copy_channels(steps_[1][t].h.get(B_, hidden_, x.h, x.w), b, 0, fin, b * S_ + t, hidden_, hidden_);
    }
  const Act y = y_.get(x.n, hidden_, x.h, x.w);
  fuse_.forward(fin, y);
  return y;
}

void WindowConvLSTM::back_direction(const Act& x, const Act& dfin, int dir, const Act& dx) {
  const int hb = (hidden_ + 15) / 16;
  auto& steps = steps_[dir];
  const Act dh_next = dh_next_.get(B_, hidden_, x.h, x.w);
  const Act dc_next = dc_next_.get(B_, hidden_, x.h, x.w);
  std::memset(dh_next.data, 0, dh_next.floats() * sizeof(float));
  std::memset(dc_next.data, 0, dc_next.floats() * sizeof(float));
  for (int k = S_ - 1; k >= 0; --k) {
    const int t = dir == 0 ? k : S_ - 1 - k;
    Step& st = steps[t];
    // dh of this step: from the fuse conv (this frame) plus from step k+1's input.
    const Act dh = dh_.get(B_, hidden_, x.h, x.w);
    for (int b = 0; b < B_; ++b) copy_channels(dfin, b * S_ + t, dir * hidden_, dh, b, 0, hidden_);
    accumulate(dh_next, dh);
    const Act dgrouped = dgrouped_.get(B_, 4 * hb * 16, x.h, x.w);
    const Act dc_prev = dc_prev_.get(B_, hidden_, x.h, x.w);
    const float* c_prev = k == 0 ? nullptr : steps[dir == 0 ? t - 1 : t + 1].c.get(B_, hidden_, x.h, x.w).data;
    kernels::lstm_kernels().bwd({B_, hb, x.pixels()}, st.act.get(B_, 4 * hb * 16, x.h, x.w).data, c_prev,
                                st.tanh_c.get(B_, hidden_, x.h, x.w).data, dh.data, dc_next.data, dgrouped.data,
                                dc_prev.data);
    Act dgates = dgrouped;
    if (hidden_ % 16) {
      dgates = dgates_.get(B_, 4 * hidden_, x.h, x.w);
      group_gates(dgates, hidden_, dgrouped, false);
    }
    const Act cat = st.cat.get(B_, in_ + hidden_, x.h, x.w);
    const Act dcat = dcat_.like(cat);
    cell_.backward(cat, dgates, &dcat);
    for (int b = 0; b < B_; ++b) {
      add_channels(dcat, b, 0, dx, b * S_ + t, 0, in_);  // dcat's x part into frame (b, t)'s dx
      copy_channels(dcat, b, in_, dh_next, b, 0, hidden_);
    }
    std::memcpy(dc_next.data, dc_prev.data, dc_prev.floats() * sizeof(float));
  }
}

void WindowConvLSTM::backward(const Act& x, const Act& dy, const Act& dx) {
  const Act fin = fuse_in_.get(x.n, bidir_ ? 2 * hidden_ : hidden_, x.h, x.w);
  const Act dfin = dfuse_in_.like(fin);
  fuse_.backward(fin, dy, &dfin);
  std::memset(dx.data, 0, dx.floats() * sizeof(float));
  back_direction(x, dfin, 0, dx);
  if (bidir_) back_direction(x, dfin, 1, dx);
}

}  // namespace yelan::layers
