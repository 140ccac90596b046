#include "layers/simple.h"

#include <algorithm>

#include <cstring>
#include <stdexcept>
#include <string>

#include "kernels/eltwise.h"
#include "kernels/vmath.h"

namespace yelan::layers {
namespace {

void same_shape(const Act& a, const Act& b, const char* what) {
  if (a.n != b.n || a.c != b.c || a.h != b.h || a.w != b.w)
    throw std::invalid_argument(std::string(what) + ": shapes differ (" + std::to_string(a.c) + "x" + std::to_string(a.h) +
                                "x" + std::to_string(a.w) + " vs " + std::to_string(b.c) + "x" + std::to_string(b.h) +
                                "x" + std::to_string(b.w) + ")");
}

// Padding lanes must stay zero (sigmoid(0) = 0.5 would break the layout's invariant).
void zero_padding(const Act& y) {
  if (y.c % 16 == 0) return;
  const int last = y.cb() - 1;
  for (int n = 0; n < y.n; ++n) {
    float* p = y.data + (std::size_t(n) * y.cb() + last) * y.pixels() * 16;
    for (std::size_t px = 0; px < y.pixels(); ++px)
      for (int l = y.c % 16; l < 16; ++l) p[px * 16 + l] = 0.f;
  }
}

// Channels [s0, s0 + count) of image sn of src beside [d0, d0 + count) of image dn of dst, in
// runs that cross no block boundary on either side: run(s, d, lanes) at pixel 0 of each run.
// With `widen`, a run that ends both maps (same lane offset) covers the padding lanes too.
template <class Run>
void channel_runs(const Act& src, int sn, int s0, const Act& dst, int dn, int d0, int count, bool widen, Run run) {
  const bool ends_both = widen && s0 + count == src.c && d0 + count == dst.c;
  while (count > 0) {
    const int len = std::min({count, 16 - s0 % 16, 16 - d0 % 16});
    const int lanes = len == count && ends_both && s0 % 16 == d0 % 16 ? 16 - s0 % 16 : len;
    run(lane_ptr(src, sn, s0, 0), lane_ptr(dst, dn, d0, 0), lanes);
    s0 += len;
    d0 += len;
    count -= len;
  }
}

}  // namespace

float* lane_ptr(const Act& a, int n, int c, std::size_t px) { return a.lane(n, c, px); }

// Whole blocks are one memcpy, and a U-Net's 24 + 24 channels move 8 or 16 lanes a pixel
// instead of one. A run that ends both maps takes the source's zero padding lanes along, so
// the destination's stay zero.
void copy_channels(const Act& src, int sn, int s0, const Act& dst, int dn, int d0, int count) {
  const std::size_t P = src.pixels();
  channel_runs(src, sn, s0, dst, dn, d0, count, true, [P](const float* s, float* d, int lanes) {
    if (lanes == 16) std::memcpy(d, s, P * 16 * sizeof(float));
    else
      for (std::size_t p = 0; p < P; ++p) std::copy_n(s + p * 16, lanes, d + p * 16);
  });
}

void add_channels(const Act& src, int sn, int s0, const Act& dst, int dn, int d0, int count) {
  const std::size_t P = src.pixels();
  channel_runs(src, sn, s0, dst, dn, d0, count, false, [P](const float* s, float* d, int lanes) {
    for (std::size_t p = 0; p < P; ++p)
      for (int l = 0; l < lanes; ++l) d[p * 16 + l] += s[p * 16 + l];
  });
}

void zero_channels(const Act& a, int n, int c0, int count) {
  const std::size_t P = a.pixels();
  channel_runs(a, n, c0, a, n, c0, count, false, [P](const float*, float* d, int lanes) {
    for (std::size_t p = 0; p < P; ++p) std::fill_n(d + p * 16, lanes, 0.f);
  });
}

void flip_frame(const Act& a, int n) {
  for (int cb = 0; cb < a.cb(); ++cb) {
    float* p = a.data + (std::size_t(n) * a.cb() + cb) * a.pixels() * 16;
    for (int y = 0; y < a.h; ++y) {
      float* row = p + std::size_t(y) * a.w * 16;
      for (int x = 0; x < a.w / 2; ++x) std::swap_ranges(row + x * 16, row + x * 16 + 16, row + (a.w - 1 - x) * 16);
    }
  }
}

void activation_forward(Activation a, const Act& x, const Act& y) {
  same_shape(x, y, "activation");
  const std::size_t n = x.floats();
  switch (a) {
    case Activation::relu: kernels::eltwise_kernels().relu(x.data, y.data, n); break;
    case Activation::sigmoid: kernels::vmath_kernels().sigmoid(x.data, y.data, n); break;
    case Activation::tanh: kernels::vmath_kernels().tanh(x.data, y.data, n); break;
  }
  // relu(0) = tanh(0) = 0 keep x's zero padding; a pass over every pixel for nothing costs
  // stage 2 (8- and 13-channel maps) about 4% of its time.
  if (a == Activation::sigmoid) zero_padding(y);
}

void activation_backward(Activation a, const Act& y, const Act& dy, const Act& dx) {
  same_shape(y, dy, "activation backward");
  const std::size_t n = y.floats();
  if (a == Activation::relu) {
    kernels::eltwise_kernels().relu_backward(y.data, dy.data, dx.data, n);
    return;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const float v = y.data[i];
    dx.data[i] = dy.data[i] * (a == Activation::sigmoid ? v * (1.f - v) : 1.f - v * v);
  }
  zero_padding(dx);
}

Act MaxPool2d::out_shape(const Act& x) const {
  const auto s = shape(x);
  return {nullptr, x.n, x.c, s.oh(), s.ow()};
}

void MaxPool2d::forward(const Act& x, const Act& y) {
  const auto s = shape(x);
  if (!s.valid()) throw std::invalid_argument("maxpool: input " + std::to_string(x.h) + "x" + std::to_string(x.w) + " too small");
  argmax_.resize(y.floats());
  kernels::pool_kernels().max_fwd(s, x.data, y.data, argmax_.data());
}

void MaxPool2d::backward(const Act& x, const Act& dy, const Act& dx) const {
  if (argmax_.size() != dy.floats()) throw std::logic_error("maxpool: backward without a matching forward");
  kernels::pool_kernels().max_bwd(shape(x), dy.data, argmax_.data(), dx.data);
}

void global_avg_pool_forward(const Act& x, const Act& y) {
  kernels::pool_kernels().avg_global_fwd(x.n * x.cb(), x.pixels(), x.data, y.data);
}
void global_avg_pool_backward(const Act& dy, const Act& dx) {
  kernels::pool_kernels().avg_global_bwd(dx.n * dx.cb(), dx.pixels(), dy.data, dx.data);
}

Linear::Linear(int in, int out) : weight("weight", {out, in}), bias("bias", {out}), in_(in), out_(out) {}

void Linear::params(const std::string& prefix, ParamList& out) {
  out.push_back({prefix + "weight", &weight});
  out.push_back({prefix + "bias", &bias});
}

void Linear::init(std::uint64_t seed) {
  init_uniform_fan_in(weight, in_, seed);
  init_uniform_fan_in(bias, in_, seed ^ 0x9e3779b97f4a7c15ull);
}

void Linear::forward(const float* x, int n, float* y) const {
  const auto& k = kernels::eltwise_kernels();
  for (int b = 0; b < n; ++b)
    for (int o = 0; o < out_; ++o) y[b * out_ + o] = bias.value[o] + k.dot(x + std::size_t(b) * in_, weight.value.data() + std::size_t(o) * in_, in_);
}

void Linear::backward(const float* x, const float* dy, int n, float* dx) {
  const auto& k = kernels::eltwise_kernels();
  if (dx) std::memset(dx, 0, std::size_t(n) * in_ * sizeof(float));
  for (int b = 0; b < n; ++b)
    for (int o = 0; o < out_; ++o) {
      const float g = dy[b * out_ + o];
      bias.grad[o] += g;
      k.axpy(g, x + std::size_t(b) * in_, weight.grad.data() + std::size_t(o) * in_, in_);
      if (dx) k.axpy(g, weight.value.data() + std::size_t(o) * in_, dx + std::size_t(b) * in_, in_);
    }
}

void copy_window(const Act& src, int sy, int sx, const Act& dst, int dy, int dx, int h, int w) {
  const auto fits = [](const Act& a, int y, int x, int h, int w) { return y >= 0 && x >= 0 && y + h <= a.h && x + w <= a.w; };
  if (src.n != dst.n || src.cb() != dst.cb() || h < 0 || w < 0 || !fits(src, sy, sx, h, w) || !fits(dst, dy, dx, h, w))
    throw std::invalid_argument("copy_window: a " + std::to_string(h) + "x" + std::to_string(w) + " window at (" +
                                std::to_string(sy) + "," + std::to_string(sx) + ") of " + std::to_string(src.h) + "x" +
                                std::to_string(src.w) + " does not go to (" + std::to_string(dy) + "," + std::to_string(dx) +
                                ") of " + std::to_string(dst.h) + "x" + std::to_string(dst.w) + " with the same blocks");
  for (int n = 0; n < src.n; ++n)
    for (int b = 0; b < src.cb(); ++b)
      for (int y = 0; y < h; ++y)
        std::memcpy(dst.data + (((std::size_t(n) * dst.cb() + b) * dst.h + dy + y) * dst.w + dx) * 16,
                    src.data + (((std::size_t(n) * src.cb() + b) * src.h + sy + y) * src.w + sx) * 16,
                    std::size_t(w) * 16 * sizeof(float));
}

void zero_window(const Act& a, int y, int x, int h, int w) {
  if (h < 0 || w < 0 || y < 0 || x < 0 || y + h > a.h || x + w > a.w)
    throw std::invalid_argument("zero_window: a " + std::to_string(h) + "x" + std::to_string(w) + " window at (" +
                                std::to_string(y) + "," + std::to_string(x) + ") is not inside " + std::to_string(a.h) +
                                "x" + std::to_string(a.w));
  for (int p = 0; p < a.n * a.cb(); ++p)
    for (int r = 0; r < h; ++r)
      std::memset(a.data + ((std::size_t(p) * a.h + y + r) * a.w + x) * 16, 0, std::size_t(w) * 16 * sizeof(float));
}

void concat_channels(const Act& a, const Act& b, const Act& y) {
  if (a.n != b.n || a.h != b.h || a.w != b.w || y.c != a.c + b.c || y.h != a.h || y.w != a.w || y.n != a.n)
    throw std::invalid_argument("concat: inputs " + std::to_string(a.c) + "x" + std::to_string(a.h) + "x" + std::to_string(a.w) +
                                " and " + std::to_string(b.c) + "x" + std::to_string(b.h) + "x" + std::to_string(b.w) +
                                " do not make " + std::to_string(y.c) + " channels");
  for (int n = 0; n < a.n; ++n) {
    copy_channels(a, n, 0, y, n, 0, a.c);
    copy_channels(b, n, 0, y, n, a.c, b.c);
  }
  zero_padding(y);
}

void concat_padded(const Act& a, const Act& b, int top, int left, const Act& y) {
  if (a.n != b.n || a.n != y.n || a.h != y.h || a.w != y.w || y.c != a.c + b.c || top < 0 || left < 0 ||
      top + b.h > y.h || left + b.w > y.w)
    throw std::invalid_argument("concat_padded: " + std::to_string(a.c) + "x" + std::to_string(a.h) + "x" + std::to_string(a.w) +
                                " and " + std::to_string(b.c) + "x" + std::to_string(b.h) + "x" + std::to_string(b.w) + " at (" +
                                std::to_string(top) + "," + std::to_string(left) + ") do not make " + std::to_string(y.c) + "x" +
                                std::to_string(y.h) + "x" + std::to_string(y.w));
  const std::size_t W = std::size_t(y.w);
  for (int n = 0; n < a.n; ++n) {
    copy_channels(a, n, 0, y, n, 0, a.c);
    channel_runs(b, n, 0, y, n, a.c, b.c, true, [&](const float* s, float* d, int lanes) {
      const auto zero = [lanes](float* p, std::size_t px) {
        if (lanes == 16) std::memset(p, 0, px * 16 * sizeof(float));
        else
          for (std::size_t i = 0; i < px; ++i) std::fill_n(p + i * 16, lanes, 0.f);
      };
      for (int r = 0; r < y.h; ++r) {
        float* row = d + std::size_t(r) * W * 16;
        if (r < top || r >= top + b.h) {
          zero(row, W);
          continue;
        }
        const float* src = s + std::size_t(r - top) * std::size_t(b.w) * 16;
        float* mid = row + std::size_t(left) * 16;
        zero(row, std::size_t(left));
        if (lanes == 16) std::memcpy(mid, src, std::size_t(b.w) * 16 * sizeof(float));
        else
          for (int x = 0; x < b.w; ++x) std::copy_n(src + std::size_t(x) * 16, lanes, mid + std::size_t(x) * 16);
        zero(mid + std::size_t(b.w) * 16, W - std::size_t(left) - std::size_t(b.w));
      }
    });
  }
  zero_padding(y);
}

void split_channels(const Act& dy, const Act& da, const Act& db) {
  for (int n = 0; n < dy.n; ++n) {
    copy_channels(dy, n, 0, da, n, 0, da.c);
    copy_channels(dy, n, da.c, db, n, 0, db.c);
  }
  zero_padding(da);
  zero_padding(db);
}

void add_forward(const Act& a, const Act& b, const Act& y) {
  same_shape(a, b, "add");
  same_shape(a, y, "add");
  kernels::eltwise_kernels().add(a.data, b.data, y.data, a.floats());
}

void accumulate(const Act& from, const Act& into) {
  same_shape(from, into, "accumulate");
  kernels::eltwise_kernels().axpy(1.f, from.data, into.data, from.floats());
}

namespace {
void check_mul(const Act& a, const Act& b, const char* what) {
  if (b.c == 1 && a.c != 1) {
    same_shape(a, Act{nullptr, b.n, a.c, b.h, b.w}, what);
    return;
  }
  same_shape(a, b, what);
}
}  // namespace

void mul_forward(const Act& a, const Act& b, const Act& y) {
  check_mul(a, b, "mul");
  same_shape(a, y, "mul");
  if (b.c == a.c) {
    for (std::size_t i = 0; i < a.floats(); ++i) y.data[i] = a.data[i] * b.data[i];
    return;
  }
  const std::size_t px = a.pixels();
  for (int n = 0; n < a.n; ++n)
    for (int cb = 0; cb < a.cb(); ++cb) {
      const float* g = b.data + std::size_t(n) * px * 16;  // lane 0 of b's only block
      const std::size_t o = (std::size_t(n) * a.cb() + cb) * px * 16;
      for (std::size_t p = 0; p < px; ++p)
        for (int l = 0; l < 16; ++l) y.data[o + p * 16 + l] = a.data[o + p * 16 + l] * g[p * 16];
    }
}

void mul_backward(const Act& a, const Act& b, const Act& dy, const Act* da, const Act* db) {
  check_mul(a, b, "mul backward");
  same_shape(a, dy, "mul backward");
  if (b.c == a.c) {
    for (std::size_t i = 0; i < a.floats(); ++i) {
      if (da) da->data[i] = dy.data[i] * b.data[i];
      if (db) db->data[i] = dy.data[i] * a.data[i];
    }
    return;
  }
  const std::size_t px = a.pixels();
  if (db) std::fill(db->data, db->data + db->floats(), 0.f);
  for (int n = 0; n < a.n; ++n)
    for (int cb = 0; cb < a.cb(); ++cb) {
      const float* g = b.data + std::size_t(n) * px * 16;
      const std::size_t o = (std::size_t(n) * a.cb() + cb) * px * 16;
      for (std::size_t p = 0; p < px; ++p) {
        float sum = 0.f;
        for (int l = 0; l < 16; ++l) {
          const std::size_t i = o + p * 16 + l;
          if (da) da->data[i] = dy.data[i] * g[p * 16];
          sum += dy.data[i] * a.data[i];  // padding lanes of a are zero
        }
        if (db) db->data[std::size_t(n) * px * 16 + p * 16] += sum;
      }
    }
}

}  // namespace yelan::layers
