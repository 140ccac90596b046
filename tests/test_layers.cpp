// Every layer's backward against central differences of its own forward (float forward,
// double sums), on odd channel counts and sizes.
#include <catch2/catch.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <functional>
#include <random>

#include "layers/batchnorm.h"
#include "layers/conv2d.h"
#include "layers/resample.h"
#include "layers/simple.h"

using namespace yelan::layers;

namespace {

// A blocked activation with its own storage; padding lanes zero.
struct Owned {
  Floats mem;
  Act act;
  Owned(int n, int c, int h, int w, unsigned seed = 0) {
    act = {nullptr, n, c, h, w};
    mem = Floats(act.floats());
    act.data = mem.data();
    if (seed) {
      std::mt19937 rng(seed);
      std::uniform_real_distribution<float> u(-1.f, 1.f);
      for_each_real([&](std::size_t i) { mem[i] = u(rng); });
    }
  }
  explicit Owned(const Act& shape, unsigned seed = 0) : Owned(shape.n, shape.c, shape.h, shape.w, seed) {}
  template <class F>
  void for_each_real(F&& f) const {
    for (int n = 0; n < act.n; ++n)
      for (int c = 0; c < act.c; ++c)
        for (std::size_t p = 0; p < act.pixels(); ++p)
          f(((std::size_t(n) * act.cb() + c / 16) * act.pixels() + p) * 16 + c % 16);
  }
};

double dot(const Act& a, const Act& b) {
  double s = 0;
  for (std::size_t i = 0; i < a.floats(); ++i) s += double(a.data[i]) * b.data[i];
  return s;
}

// Checks d<w, f(x)>/dv for sampled entries v of `values` against `grad`.
void check_fd(const std::function<double()>& loss, float* values, std::size_t count, const float* grad,
              std::size_t stride, double h, double tol, const char* what) {
  for (std::size_t i = 0; i < count; i += stride) {
    const float saved = values[i];
    values[i] = saved + float(h);
    const double lp = loss();
    values[i] = saved - float(h);
    const double lm = loss();
    values[i] = saved;
    const double fd = (lp - lm) / (2 * h);
    INFO(what << "[" << i << "] analytic " << grad[i] << " numeric " << fd);
    REQUIRE(std::abs(grad[i] - fd) <= tol * (1 + std::abs(fd)));
  }
}

void check_input_fd(const std::function<double()>& loss, Owned& x, const Act& dx, std::size_t stride, double h,
                    double tol) {
  std::size_t k = 0;
  x.for_each_real([&](std::size_t i) {
    if (k++ % stride) return;
    const float saved = x.mem[i];
    x.mem[i] = saved + float(h);
    const double lp = loss();
    x.mem[i] = saved - float(h);
    const double lm = loss();
    x.mem[i] = saved;
    const double fd = (lp - lm) / (2 * h);
    INFO("dx[" << i << "] analytic " << dx.data[i] << " numeric " << fd);
    REQUIRE(std::abs(dx.data[i] - fd) <= tol * (1 + std::abs(fd)));
  });
}

}  // namespace

TEST_CASE("Conv2d and ConvTranspose2d layers: gradients by finite differences", "[layers][conv]") {
  struct C { ConvSpec spec; int n, h, w; };
  for (const C& c : {C{{3, 13, 3, 1, 1, true}, 2, 7, 5}, C{{17, 5, 3, 2, 1, false}, 1, 9, 7},
                     C{{6, 16, 7, 2, 3, true}, 1, 11, 13}, C{{5, 3, 1, 2, 0, true}, 1, 5, 4},
                     C{{13, 7, 3, 2, 1, true, true, 0, 1}, 1, 4, 5}, C{{8, 3, 2, 2, 0, true, true}, 2, 3, 3}}) {
    Conv2d layer(c.spec);
    layer.init(7);
    Owned x(c.n, c.spec.in, c.h, c.w, 1);
    const Act ys = layer.out_shape(x.act);
    Owned y(ys), w(ys, 2), dx(x.act);
    auto loss = [&] {
      layer.weights_changed();
      layer.forward(x.act, y.act);
      return dot(w.act, y.act);
    };
    loss();
    layer.backward(x.act, w.act, &dx.act);
    INFO("conv " << c.spec.in << "->" << c.spec.out << " k" << c.spec.k << " s" << c.spec.stride
                 << (c.spec.transposed ? " transposed" : ""));
    check_input_fd(loss, x, dx.act, 3, 1e-2, 2e-3);
    check_fd(loss, layer.weight.value.data(), layer.weight.numel(), layer.weight.grad.data(), 5, 1e-2, 2e-3, "dw");
    if (layer.bias) check_fd(loss, layer.bias->value.data(), layer.bias->numel(), layer.bias->grad.data(), 1, 1e-2, 2e-3, "db");
    // Gradients accumulate: a second backward doubles them.
    const float g0 = layer.weight.grad[0];
    layer.backward(x.act, w.act, nullptr);
    CHECK(layer.weight.grad[0] == Approx(2 * g0).epsilon(1e-5).margin(1e-6));
  }
}

TEST_CASE("Winograd layer forward equals the direct forward", "[layers][conv]") {
  Conv2d layer({20, 24, 3, 1, 1, true});
  layer.init(3);
  Owned x(1, 20, 13, 11, 4);
  Owned y1(layer.out_shape(x.act)), y2(layer.out_shape(x.act));
  layer.forward(x.act, y1.act, false);
  layer.forward(x.act, y2.act, true);
  for (std::size_t i = 0; i < y1.act.floats(); ++i) REQUIRE(y2.mem[i] == Approx(y1.mem[i]).margin(1e-4));
}

TEST_CASE("BatchNorm2d: training gradients, running statistics, eval mode", "[layers][bn]") {
  {
    BatchNorm2d bn(19);
    for (int i = 0; i < 19; ++i) {
      bn.weight.value[i] = 0.5f + 0.05f * i;
      bn.bias.value[i] = 0.1f * (i % 5) - 0.2f;
    }
    Owned x(2, 19, 5, 3, 5), y(x.act), w(x.act, 6), dx(x.act);
    auto loss = [&] {
      bn.forward(x.act, y.act);
      return dot(w.act, y.act);
    };
    loss();
    bn.backward(x.act, y.act, w.act, dx.act);
    check_input_fd(loss, x, dx.act, 2, 1e-2, 3e-3);
    check_fd(loss, bn.weight.value.data(), 19, bn.weight.grad.data(), 1, 1e-2, 2e-3, "dgamma");
    check_fd(loss, bn.bias.value.data(), 19, bn.bias.grad.data(), 1, 1e-2, 2e-3, "dbeta");
  }
  {
    // Fused ReLU equals BN followed by ReLU, forward and backward (finite differences do
    // not suit the kink: shifting one input moves the batch mean of every output).
    BatchNorm2d fused(19, true), plain(19, false);
    for (int i = 0; i < 19; ++i) fused.weight.value[i] = plain.weight.value[i] = 0.3f + 0.1f * i;
    Owned x(2, 19, 5, 3, 5), y1(x.act), y2(x.act), r(x.act), w(x.act, 6), dx1(x.act), dx2(x.act), dr(x.act);
    fused.forward(x.act, y1.act);
    plain.forward(x.act, y2.act);
    activation_forward(Activation::relu, y2.act, r.act);
    for (std::size_t i = 0; i < x.act.floats(); ++i) REQUIRE(y1.mem[i] == Approx(r.mem[i]).margin(1e-6));
    fused.backward(x.act, y1.act, w.act, dx1.act);
    activation_backward(Activation::relu, r.act, w.act, dr.act);
    plain.backward(x.act, y2.act, dr.act, dx2.act);
    for (std::size_t i = 0; i < x.act.floats(); ++i) REQUIRE(dx1.mem[i] == Approx(dx2.mem[i]).margin(1e-5));
    for (int i = 0; i < 19; ++i) REQUIRE(fused.weight.grad[i] == Approx(plain.weight.grad[i]).margin(1e-5));
  }
  // Running statistics: momentum 0.1, unbiased variance; eval uses them.
  BatchNorm2d bn(3);
  Owned x(1, 3, 2, 2, 0);
  const float vals[4] = {1, 2, 3, 6};  // mean 3, biased var 3.5, unbiased 14/3
  for (int p = 0; p < 4; ++p) x.mem[p * 16 + 1] = vals[p];
  Owned y(x.act);
  bn.forward(x.act, y.act);
  CHECK(bn.running_mean.value[1] == Approx(0.3f));
  CHECK(bn.running_var.value[1] == Approx(0.9f + 0.1f * 14.f / 3.f));
  CHECK(bn.num_batches_tracked.value[0] == 1.f);
  CHECK(y.mem[0 * 16 + 1] == Approx((1 - 3) / std::sqrt(3.5 + 1e-5)));
  bn.training = false;
  bn.forward(x.act, y.act);
  CHECK(y.mem[3 * 16 + 1] == Approx((6 - 0.3) / std::sqrt(0.9 + 0.1 * 14.0 / 3 + 1e-5)));
  CHECK(bn.num_batches_tracked.value[0] == 1.f);  // eval does not count batches
}

TEST_CASE("activations, pooling, linear and concatenation: gradients by finite differences", "[layers][simple]") {
  for (Activation a : {Activation::relu, Activation::sigmoid, Activation::tanh}) {
    Owned x(1, 13, 3, 5, 8), y(x.act), w(x.act, 9), dx(x.act);
    x.for_each_real([&](std::size_t i) {  // keep inputs off ReLU's kink by more than the step
      if (std::abs(x.mem[i]) < 0.01f) x.mem[i] = x.mem[i] < 0 ? -0.01f : 0.01f;
    });
    auto loss = [&] {
      activation_forward(a, x.act, y.act);
      return dot(w.act, y.act);
    };
    loss();
    for (std::size_t i = 13; i < 16; ++i) REQUIRE(y.mem[i] == 0.f);  // padding lanes stay zero
    activation_backward(a, y.act, w.act, dx.act);
    check_input_fd(loss, x, dx.act, 1, 1e-3, 2e-3);
  }
  {
    MaxPool2d pool(3, 2, 1);
    Owned x(2, 7, 9, 6, 10);
    Owned y(pool.out_shape(x.act)), w(pool.out_shape(x.act), 11), dx(x.act);
    auto loss = [&] {
      pool.forward(x.act, y.act);
      return dot(w.act, y.act);
    };
    loss();
    pool.backward(x.act, w.act, dx.act);
    check_input_fd(loss, x, dx.act, 1, 1e-4, 1e-3);
  }
  {
    Owned x(2, 21, 4, 3, 12), pooled(2, 21, 1, 1), dpooled(2, 21, 1, 1), dx(x.act);
    Linear fc(32, 5);  // 21 channels live in 2 blocks of 16 lanes: 32 features, padding zero
    fc.init(13);
    std::vector<float> y(10), wv(10), dfeat(64);
    std::mt19937 rng(14);
    for (auto& v : wv) v = std::uniform_real_distribution<float>(-1, 1)(rng);
    auto loss = [&] {
      global_avg_pool_forward(x.act, pooled.act);
      fc.forward(pooled.mem.data(), 2, y.data());
      double s = 0;
      for (int i = 0; i < 10; ++i) s += double(y[i]) * wv[i];
      return s;
    };
    loss();
    fc.backward(pooled.mem.data(), wv.data(), 2, dpooled.mem.data());
    global_avg_pool_backward(dpooled.act, dx.act);
    check_input_fd(loss, x, dx.act, 3, 1e-2, 2e-3);
    check_fd(loss, fc.weight.value.data(), fc.weight.numel(), fc.weight.grad.data(), 3, 1e-2, 2e-3, "linear dw");
    check_fd(loss, fc.bias.value.data(), 5, fc.bias.grad.data(), 1, 1e-2, 2e-3, "linear db");
  }
  // Every lane of every pixel of both images, the padding lanes zero: runs that cross a
  // block boundary on one side only (13 + 26, 24 + 24, 8 + 13) as well as whole blocks.
  for (auto [ca, cb] : {std::pair{13, 26}, std::pair{16, 5}, std::pair{3, 3}, std::pair{24, 24}, std::pair{8, 13},
                        std::pair{32, 16}}) {
    INFO(ca << " + " << cb << " channels");
    Owned a(2, ca, 3, 2, 15), b(2, cb, 3, 2, 16), y(2, ca + cb, 3, 2), da(a.act), db(b.act);
    std::fill_n(y.mem.data(), y.act.floats(), 7.f);  // the padding must be written, not assumed
    concat_channels(a.act, b.act, y.act);
    const auto at = [](const Owned& o, int n, int c, int p) {
      return o.mem[((std::size_t(n) * o.act.cb() + c / 16) * 6 + p) * 16 + c % 16];
    };
    for (int n = 0; n < 2; ++n)
      for (int p = 0; p < 6; ++p)
        for (int c = 0; c < y.act.cb() * 16; ++c)
          REQUIRE(at(y, n, c, p) == (c >= ca + cb ? 0.f : c < ca ? at(a, n, c, p) : at(b, n, c - ca, p)));
    split_channels(y.act, da.act, db.act);
    for (std::size_t i = 0; i < a.act.floats(); ++i) REQUIRE(da.mem[i] == a.mem[i]);
    for (std::size_t i = 0; i < b.act.floats(); ++i) REQUIRE(db.mem[i] == b.mem[i]);
  }
  // Between images: only the named lanes change, except that a copy ending both maps at the
  // same lane offset (the ConvLSTM's [x, h] with 16-aligned x) brings the zero padding along.
  for (auto [s0, d0, count, c_dst] : {std::array{5, 21, 14, 40}, std::array{3, 19, 16, 35}, std::array{0, 16, 19, 35}}) {
    INFO(count << " channels from " << s0 << " to " << d0 << " of " << c_dst);
    Owned src(3, s0 + count, 2, 3, 31), dst(2, c_dst, 2, 3);
    std::fill_n(dst.mem.data(), dst.act.floats(), 7.f);
    copy_channels(src.act, 2, s0, dst.act, 1, d0, count);
    const bool ends_both = d0 + count == c_dst && s0 % 16 == d0 % 16;
    for (int n = 0; n < 2; ++n)
      for (int c = 0; c < dst.act.cb() * 16; ++c)
        for (std::size_t p = 0; p < 6; ++p) {
          const float got = *lane_ptr(dst.act, n, c, p);
          if (n == 1 && c >= d0 && c < d0 + count) REQUIRE(got == *lane_ptr(src.act, 2, c - d0 + s0, p));
          else if (n == 1 && c >= c_dst && ends_both) REQUIRE(got == 0.f);
          else REQUIRE(got == 7.f);
        }
  }
  // add_channels and zero_channels touch the named lanes only, padding included (the ConvLSTM's
  // dx += dcat's x part, and its first step's zero h).
  for (auto [s0, d0, count, c_dst] : {std::array{5, 21, 14, 40}, std::array{3, 19, 16, 35}, std::array{0, 16, 19, 35}}) {
    INFO(count << " channels from " << s0 << " to " << d0 << " of " << c_dst);
    Owned src(3, s0 + count, 2, 3, 37), dst(2, c_dst, 2, 3), zeroed(2, c_dst, 2, 3);
    std::fill_n(dst.mem.data(), dst.act.floats(), 7.f);
    std::fill_n(zeroed.mem.data(), zeroed.act.floats(), 7.f);
    add_channels(src.act, 2, s0, dst.act, 1, d0, count);
    zero_channels(zeroed.act, 1, d0, count);
    for (int n = 0; n < 2; ++n)
      for (int c = 0; c < dst.act.cb() * 16; ++c)
        for (std::size_t p = 0; p < 6; ++p) {
          const bool named = n == 1 && c >= d0 && c < d0 + count;
          REQUIRE(*lane_ptr(dst.act, n, c, p) == (named ? 7.f + *lane_ptr(src.act, 2, c - d0 + s0, p) : 7.f));
          REQUIRE(*lane_ptr(zeroed.act, n, c, p) == (named ? 0.f : 7.f));
        }
  }
}

TEST_CASE("avg_pool and bilinear resize: PyTorch's values, and each backward the forward's adjoint", "[layers][resample]") {
  // F.interpolate([[1, 2], [3, 4]], size=(4, 4), mode='bilinear', align_corners=False)
  Owned x(1, 1, 2, 2), y(1, 1, 4, 4);
  for (int i = 0; i < 4; ++i) x.mem[std::size_t(i) * 16] = float(i + 1);
  resize_bilinear_forward(x.act, y.act);
  const float want[16] = {1, 1.25f, 1.75f, 2, 1.5f, 1.75f, 2.25f, 2.5f, 2.5f, 2.75f, 3.25f, 3.5f, 3, 3.25f, 3.75f, 4};
  for (int i = 0; i < 16; ++i) REQUIRE(y.mem[std::size_t(i) * 16] == Approx(want[i]).margin(1e-6));
  // F.avg_pool2d over a 3 x 5 map, k 2: one 1 x 2 output, the last row and column dropped
  Owned p(1, 1, 3, 5), q(1, 1, 1, 2);
  for (int i = 0; i < 15; ++i) p.mem[std::size_t(i) * 16] = float(i);
  avg_pool_forward(p.act, 2, q.act);
  REQUIRE(q.mem[0] == Approx((0 + 1 + 5 + 6) / 4.0));
  REQUIRE(q.mem[16] == Approx((2 + 3 + 7 + 8) / 4.0));
  // <forward(a), b> == <a, backward(b)> on odd shapes, both directions of resizing
  const auto dot = [](const Act& u, const Act& v) {
    double sum = 0;
    for (std::size_t i = 0; i < u.floats(); ++i) sum += double(u.data[i]) * v.data[i];
    return sum;
  };
  struct Case { int n, c, h, w, oh, ow; };
  for (const Case& k : {Case{2, 21, 7, 11, 13, 23}, Case{1, 5, 65, 86, 130, 173}, Case{1, 16, 13, 9, 5, 4}}) {
    INFO(k.h << "x" << k.w << " -> " << k.oh << "x" << k.ow);
    Owned a(k.n, k.c, k.h, k.w, 41), b(k.n, k.c, k.oh, k.ow, 42), fa(b.act), bb(a.act);
    resize_bilinear_forward(a.act, fa.act);
    resize_bilinear_backward(b.act, bb.act);
    REQUIRE(dot(fa.act, b.act) == Approx(dot(a.act, bb.act)).epsilon(1e-5));
  }
  for (int k : {2, 3}) {
    Owned a(2, 19, 11, 8, 43), b(2, 19, 11 / k, 8 / k, 44), fa(b.act), bb(a.act);
    avg_pool_forward(a.act, k, fa.act);
    avg_pool_backward(b.act, k, bb.act);
    REQUIRE(dot(fa.act, b.act) == Approx(dot(a.act, bb.act)).epsilon(1e-5));
  }
  CHECK_THROWS_AS(avg_pool_forward(p.act, 2, y.act), std::invalid_argument);
}

TEST_CASE("copy_window moves a window between maps of any size, element by element, and refuses one that does not fit", "[layers][simple]") {
  struct Case { int n, c, sh, sw, dh, dw, sy, sx, dy, dx, h, w; };
  for (const Case& k : {Case{1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 1, 1}, Case{2, 17, 7, 3, 33, 44, 2, 1, 30, 40, 3, 2},
                        Case{1, 33, 33, 44, 7, 17, 13, 5, 0, 3, 7, 14}, Case{3, 16, 5, 5, 5, 5, 0, 0, 0, 0, 5, 5},
                        Case{1, 3, 4, 4, 6, 6, 1, 1, 2, 2, 0, 3}}) {
    INFO(k.c << " channels, " << k.h << "x" << k.w << " from " << k.sh << "x" << k.sw << " to " << k.dh << "x" << k.dw);
    Owned src(k.n, k.c, k.sh, k.sw, 31), dst(k.n, k.c, k.dh, k.dw, 32), before(dst.act);
    std::memcpy(before.mem.data(), dst.mem.data(), dst.mem.size() * sizeof(float));
    copy_window(src.act, k.sy, k.sx, dst.act, k.dy, k.dx, k.h, k.w);
    auto at = [](const Owned& o, int n, int c, int y, int x) {
      return o.mem[((std::size_t(n) * o.act.cb() + c / 16) * o.act.h + y) * o.act.w * 16 + std::size_t(x) * 16 + c % 16];
    };
    for (int n = 0; n < k.n; ++n)
      for (int c = 0; c < k.c; ++c)
        for (int y = 0; y < k.dh; ++y)
          for (int x = 0; x < k.dw; ++x) {
            const bool inside = y >= k.dy && y < k.dy + k.h && x >= k.dx && x < k.dx + k.w;
            REQUIRE(at(dst, n, c, y, x) == (inside ? at(src, n, c, y - k.dy + k.sy, x - k.dx + k.sx) : at(before, n, c, y, x)));
          }
  }
  Owned a(1, 17, 5, 6), b(1, 17, 4, 4), thin(1, 3, 4, 4), other(2, 17, 4, 4);
  CHECK_THROWS_AS(copy_window(a.act, 0, 0, b.act, 0, 0, 5, 1), std::invalid_argument);   // too tall for dst
  CHECK_THROWS_AS(copy_window(a.act, 2, 3, b.act, 0, 0, 3, 4), std::invalid_argument);   // off src's edge
  CHECK_THROWS_AS(copy_window(a.act, -1, 0, b.act, 0, 0, 1, 1), std::invalid_argument);
  CHECK_THROWS_AS(copy_window(a.act, 0, 0, thin.act, 0, 0, 1, 1), std::invalid_argument);  // other blocks
  CHECK_THROWS_AS(copy_window(a.act, 0, 0, other.act, 0, 0, 1, 1), std::invalid_argument); // other images
  CHECK_NOTHROW(copy_window(a.act, 1, 2, b.act, 0, 0, 4, 4));
}

TEST_CASE("concat_padded writes [a, F.pad(b)] element by element, padding lanes zero, over a dirty buffer", "[layers][simple]") {
  struct Case { int n, ca, cb, h, w, bh, bw, top, left; };
  for (const Case& k : {Case{1, 24, 24, 130, 173, 128, 172, 1, 0}, Case{2, 5, 7, 9, 11, 8, 10, 0, 1},
                        Case{1, 16, 16, 5, 6, 4, 4, 1, 1}, Case{2, 20, 13, 7, 7, 7, 7, 0, 0}, Case{1, 48, 48, 17, 22, 16, 20, 0, 1}}) {
    INFO(k.ca << " + " << k.cb << " channels, " << k.bh << "x" << k.bw << " at (" << k.top << "," << k.left << ") of " << k.h << "x" << k.w);
    Owned a(k.n, k.ca, k.h, k.w, 41), b(k.n, k.cb, k.bh, k.bw, 42), y(k.n, k.ca + k.cb, k.h, k.w);
    std::fill(y.mem.data(), y.mem.data() + y.mem.size(), 7.f);  // a reused buffer: nothing may survive
    concat_padded(a.act, b.act, k.top, k.left, y.act);
    auto at = [](const Owned& o, int n, int c, int yy, int x) {
      return o.mem[((std::size_t(n) * o.act.cb() + c / 16) * o.act.h + yy) * o.act.w * 16 + std::size_t(x) * 16 + c % 16];
    };
    for (int n = 0; n < k.n; ++n)
      for (int c = 0; c < y.act.cb() * 16; ++c)
        for (int yy = 0; yy < k.h; ++yy)
          for (int x = 0; x < k.w; ++x) {
            float want = 0;
            if (c < k.ca) want = at(a, n, c, yy, x);
            else if (c < k.ca + k.cb && yy >= k.top && yy < k.top + k.bh && x >= k.left && x < k.left + k.bw)
              want = at(b, n, c - k.ca, yy - k.top, x - k.left);
            REQUIRE(at(y, n, c, yy, x) == want);
          }
  }
  Owned a(1, 8, 5, 6), b(1, 8, 4, 4), y(1, 16, 5, 6), y2(1, 17, 5, 6);
  CHECK_THROWS_AS(concat_padded(a.act, b.act, 2, 0, y.act), std::invalid_argument);   // b off y's bottom
  CHECK_THROWS_AS(concat_padded(a.act, b.act, 0, -1, y.act), std::invalid_argument);
  CHECK_THROWS_AS(concat_padded(a.act, b.act, 0, 0, y2.act), std::invalid_argument);  // the channels do not add up
  CHECK_NOTHROW(concat_padded(a.act, b.act, 1, 2, y.act));
}

TEST_CASE("zero_window clears a window of every image and block, nothing else, and refuses one that does not fit", "[layers][simple]") {
  struct Case { int n, c, h, w, y, x, wh, ww; };
  for (const Case& k : {Case{1, 1, 1, 1, 0, 0, 1, 1}, Case{2, 17, 7, 9, 2, 1, 3, 5}, Case{1, 33, 5, 6, 0, 5, 5, 1},
                        Case{3, 6, 4, 4, 1, 1, 0, 2}}) {
    INFO(k.c << " channels, a " << k.wh << "x" << k.ww << " window at (" << k.y << "," << k.x << ") of " << k.h << "x" << k.w);
    Owned a(k.n, k.c, k.h, k.w, 33), before(a.act);
    std::memcpy(before.mem.data(), a.mem.data(), a.mem.size() * sizeof(float));
    zero_window(a.act, k.y, k.x, k.wh, k.ww);
    for (std::size_t i = 0; i < a.mem.size(); ++i) {
      const std::size_t px = i / 16 % a.act.pixels();
      const int y = int(px) / k.w, x = int(px) % k.w;
      const bool inside = y >= k.y && y < k.y + k.wh && x >= k.x && x < k.x + k.ww;
      REQUIRE(a.mem[i] == (inside ? 0.f : before.mem[i]));
    }
  }
  Owned a(1, 17, 5, 6);
  CHECK_THROWS_AS(zero_window(a.act, 0, 0, 6, 1), std::invalid_argument);   // too tall
  CHECK_THROWS_AS(zero_window(a.act, 2, 3, 3, 4), std::invalid_argument);   // off the right edge
  CHECK_THROWS_AS(zero_window(a.act, -1, 0, 1, 1), std::invalid_argument);
  CHECK_NOTHROW(zero_window(a.act, 0, 0, 5, 6));
}

TEST_CASE("elementwise mul, same shape and a one-channel gate: gradients by finite differences", "[layers][simple]") {
  for (auto [c, gc] : {std::pair{13, 13}, std::pair{6, 1}, std::pair{17, 1}, std::pair{1, 1}}) {
    INFO(c << " channels times " << gc);
    Owned a(2, c, 7, 3, 21), b(2, gc, 7, 3, 22), y(a.act), w(a.act, 23), da(a.act), db(b.act);
    auto loss = [&] {
      mul_forward(a.act, b.act, y.act);
      return dot(w.act, y.act);
    };
    loss();
    // hand check of one element: channel c-1, pixel (6, 2) of the second sample
    const std::size_t px = 21, i = ((1 * a.act.cb() + (c - 1) / 16) * px + 6 * 3 + 2) * 16 + (c - 1) % 16;
    const std::size_t j = gc == 1 ? (1 * px + 6 * 3 + 2) * 16 : i;
    REQUIRE(y.mem[i] == a.mem[i] * b.mem[j]);
    for (int l = c % 16; c % 16 && l < 16; ++l) REQUIRE(y.mem[(a.act.cb() - 1) * px * 16 + l] == 0.f);
    mul_backward(a.act, b.act, w.act, &da.act, &db.act);
    check_input_fd(loss, a, da.act, 3, 1e-3, 1e-3);
    check_input_fd(loss, b, db.act, 3, 1e-3, 1e-3);
  }
  Owned a(1, 6, 4, 4), b(1, 2, 4, 4), y(a.act);
  CHECK_THROWS_AS(mul_forward(a.act, b.act, y.act), std::invalid_argument);
}

#include "engine/adam.h"

TEST_CASE("Adam: PyTorch's update, decay, LR steps, clipping, and exact state restore", "[layers][adam]") {
  auto make = [] {
    auto p = std::make_unique<Param>("w", std::vector<std::int64_t>{3});
    for (int i = 0; i < 3; ++i) p->value[i] = 0.5f * (i + 1);
    return p;
  };
  auto pa = make();
  ParamList list{{"w", pa.get()}};
  yelan::AdamOptions o;
  o.lr = 0.1;
  o.weight_decay = 0.01;
  o.step_size = 2;
  o.gamma = 0.5;
  yelan::Adam adam(list, o);
  // One step by hand: g = grad + wd w; m = 0.1 g; v = 0.001 g^2; w -= lr m/(1-0.9) / (sqrt(v/(1-0.999)) + eps)
  const float grads[3] = {1.f, -2.f, 0.f};
  for (int i = 0; i < 3; ++i) pa->grad[i] = grads[i];
  adam.step();
  for (int i = 0; i < 3; ++i) {
    const double w0 = 0.5 * (i + 1), g = grads[i] + 0.01 * w0;
    const double m = 0.1 * g / 0.1, v = std::sqrt(0.001 * g * g / 0.001);
    CHECK(pa->value[i] == Approx(w0 - 0.1 * m / (v + 1e-8)).epsilon(1e-6));
  }
  // LR schedule: halved every 2 epochs
  adam.end_epoch();
  CHECK(adam.lr() == Approx(0.1));
  adam.end_epoch();
  CHECK(adam.lr() == Approx(0.05));
  // State restore: a copy continued from the saved state steps exactly as the original.
  auto pb = make();
  for (int i = 0; i < 3; ++i) pb->value[i] = pa->value[i];
  ParamList list_b{{"w", pb.get()}};
  yelan::Adam copy(list_b, o);
  copy.set_state(adam.moments(), adam.steps(), adam.epochs(), adam.lr());
  for (int k = 0; k < 3; ++k) {
    for (int i = 0; i < 3; ++i) pa->grad[i] = pb->grad[i] = 0.3f * (k + 1) - 0.2f * i;
    adam.step();
    copy.step();
  }
  for (int i = 0; i < 3; ++i) CHECK(pa->value[i] == pb->value[i]);
  CHECK_THROWS_AS(copy.set_state(std::vector<float>(5), 1, 0, 0.1), std::invalid_argument);
  // Clipping scales the whole gradient to the norm bound before the moments.
  auto pc = make();
  ParamList lc{{"w", pc.get()}};
  yelan::AdamOptions oc = o;
  oc.weight_decay = 0;
  oc.clip_norm = 1.0;
  yelan::Adam clipped(lc, oc);
  for (int i = 0; i < 3; ++i) pc->grad[i] = 30.f * (i + 1);
  CHECK(clipped.step() == Approx(30.0 * std::sqrt(14.0)));
  // Adam's first step does not depend on the gradient's scale: check the moments instead.
  const auto mv = clipped.moments();
  const double scale = 1.0 / (30.0 * std::sqrt(14.0) + 1e-6);
  CHECK(mv[0] == Approx(0.1 * 30.0 * scale).epsilon(1e-5));
}
