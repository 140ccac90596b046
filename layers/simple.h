// Parameter-free layers and Linear: activations, pooling, channel concatenation, sums.
#pragma once
#include <cstddef>
#include <cstdint>
#include <vector>

#include "kernels/pool.h"
#include "layers/param.h"

namespace yelan::layers {

enum class Activation { relu, sigmoid, tanh };
void activation_forward(Activation a, const Act& x, const Act& y);
// dx from dy and the forward's output y (relu: y > 0; sigmoid: y(1-y); tanh: 1-y^2).
void activation_backward(Activation a, const Act& y, const Act& dy, const Act& dx);

class MaxPool2d {
 public:
  MaxPool2d(int k, int stride, int pad) : k_(k), stride_(stride), pad_(pad) {}
  Act out_shape(const Act& x) const;
  void forward(const Act& x, const Act& y);
  void backward(const Act& x, const Act& dy, const Act& dx) const;  // through the last forward's argmax

 private:
  int k_, stride_, pad_;
  std::vector<std::int32_t> argmax_;
  kernels::PoolShape shape(const Act& x) const { return {x.n * x.cb(), x.h, x.w, k_, stride_, pad_}; }
};

// Mean over all pixels: y is n x cb x 1 x 1 x 16.
void global_avg_pool_forward(const Act& x, const Act& y);
void global_avg_pool_backward(const Act& dy, const Act& dx);

// y = x W^T + b on n vectors of `in` features (plain arrays, not blocked).
class Linear {
 public:
  Linear(int in, int out);
  Param weight, bias;
  void params(const std::string& prefix, ParamList& out);
  void init(std::uint64_t seed);
  void forward(const float* x, int n, float* y) const;
  void backward(const float* x, const float* dy, int n, float* dx);  // dx may be null
  int in() const { return in_; }
  int out() const { return out_; }

 private:
  int in_, out_;
};

// Copies the h x w window at (sy, sx) of every image and channel block of `src` to (dy, dx)
// of `dst` (same images and channel blocks, any sizes): padding a map into a larger one,
// cropping it back out (the adjoint), or pasting a crop's features into the frame's.
void copy_window(const Act& src, int sy, int sx, const Act& dst, int dy, int dx, int h, int w);
// The h x w window at (y, x) of every image and channel block of `a` set to zero.
void zero_window(const Act& a, int y, int x, int h, int w);

// Frame n of `a` mirrored left to right in place, every channel: cell x trades with cell w - 1 - x.
void flip_frame(const Act& a, int n);

// Address of channel c of pixel px of image n in the blocked layout (n, c/16, pixel, c%16).
float* lane_ptr(const Act& a, int n, int c, std::size_t px);
// Channels [s0, s0 + count) of image sn of src to [d0, d0 + count) of image dn of dst (same
// pixels, any channel offsets and counts).
void copy_channels(const Act& src, int sn, int s0, const Act& dst, int dn, int d0, int count);
// The same channels added into dst (dst += src), and channels of one image set to zero.
void add_channels(const Act& src, int sn, int s0, const Act& dst, int dn, int d0, int count);
void zero_channels(const Act& a, int n, int c0, int count);

// Channel concatenation [a, b] -> y and its backward split (any channel counts).
void concat_channels(const Act& a, const Act& b, const Act& y);
// [a, F.pad(b)] -> y in one pass: b's window at (top, left) of y's channels a.c.., zero around
// it; a as large as y. The U-Net's up path, without the padded map written and read again.
void concat_padded(const Act& a, const Act& b, int top, int left, const Act& y);
void split_channels(const Act& dy, const Act& da, const Act& db);

// y = a + b; dy passes unchanged to both inputs, so backward is a copy or an add.
void add_forward(const Act& a, const Act& b, const Act& y);
void accumulate(const Act& from, const Act& into);  // into += from

// y = a * b elementwise; b may instead have one channel, a per-pixel gate broadcast over a's
// channels (the human mask applied to every TORE channel). Backward: da = dy * b and
// db = dy * a, summed over channels when b was broadcast; a null da or db is skipped.
void mul_forward(const Act& a, const Act& b, const Act& y);
void mul_backward(const Act& a, const Act& b, const Act& dy, const Act* da, const Act* db);

}  // namespace yelan::layers
