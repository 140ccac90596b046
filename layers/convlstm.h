// One ConvLSTM layer over windows of S frames (SPEC 5): gates = conv3x3(cat[x, h]) split
// i, f, o, g; c' = f c + i g; h' = o tanh(c'); zero state per window. Bidirectional runs
// the SAME cell forward and backward in time and fuses cat[h_fwd, h_bwd] with a 1x1 conv
// (2 hidden -> hidden); causal runs forward only (fuse hidden -> hidden). Backward is BPTT
// through the whole window. Names: cell_list.0.conv.*, fuse_list.0.*.
#pragma once
#include <vector>

#include "layers/buffer.h"
#include "layers/conv2d.h"

namespace yelan::layers {

class WindowConvLSTM {
 public:
  WindowConvLSTM(int in, int hidden, bool bidirectional);
  void params(const std::string& prefix, ParamList& out);
  void init(std::uint64_t seed);
  void weights_changed();
  // x holds B windows of S frames: frame t of window b is image b*S + t. y: B*S x hidden.
  Act forward(const Act& x, int frames_per_window);
  void backward(const Act& x, const Act& dy, const Act& dx);
  int hidden() const { return hidden_; }
  // Streaming (causal only, one window of any length per call): each forward starts from the
  // state the previous one ended in, instead of zeros; reset_state() starts afresh. Frame k
  // of a window then costs one step, and gives what the window forward gives for frame k.
  void set_streaming(bool on);
  void reset_state() { have_state_ = false; }

 private:
  struct Step {  // what BPTT needs from one time step of one direction
    ActBuf cat, act, c, tanh_c, h;
  };
  int in_, hidden_, S_ = 0, B_ = 0;
  bool bidir_;
  bool streaming_ = false, have_state_ = false;
  Floats carry_h_, carry_c_;
  Conv2d cell_, fuse_;
  std::vector<Step> steps_[2];
  ActBuf gates_, grouped_, fuse_in_, y_, dfuse_in_, dgrouped_, dgates_, dcat_, dh_next_, dc_next_, dc_prev_, dh_;

  void run_direction(const Act& x, int dir);
  void back_direction(const Act& x, const Act& dfuse_in, int dir, const Act& dx);
};

}  // namespace yelan::layers
