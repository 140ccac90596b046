#include "layers/resample.h"

#include <algorithm>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

namespace yelan::layers {
namespace {

void check_images(const Act& a, const Act& b, const char* what) {
  if (a.n != b.n || a.c != b.c)
    throw std::invalid_argument(std::string(what) + ": " + std::to_string(a.n) + " x " + std::to_string(a.c) +
                                " channels in, " + std::to_string(b.n) + " x " + std::to_string(b.c) + " out");
}

// One axis of PyTorch's bilinear sampling: output index -> (i0, i1, weight of i1).
struct Tap {
  int i0, i1;
  float l1;
};
std::vector<Tap> taps(int in, int out) {
  const float scale = float(in) / float(out);  // in float, as PyTorch's CPU kernel for float maps
  std::vector<Tap> t(static_cast<std::size_t>(out));
  for (int o = 0; o < out; ++o) {
    const float src = std::max(0.f, scale * (float(o) + 0.5f) - 0.5f);
    const int i0 = std::min(int(src), in - 1);
    t[std::size_t(o)] = {i0, i0 < in - 1 ? i0 + 1 : i0, src - float(i0)};
  }
  return t;
}

float* px(const Act& a, int n, int cb, int y, int x) { return a.lane(n, cb * 16, std::size_t(y) * a.w + x); }

// The input pixels one output pixel of a bilinear resize samples: (i0, j0), (i0, j1), (i1, j0),
// (i1, j1), with weights from the row's and column's fractions.
struct Nbr {
  float* p[4];
};

// Calls f(neighbours in `in`, row fraction, column fraction, the pixel of `out`) for every
// output pixel of every image and channel block: the forward gathers through it, the
// backward scatters (its `in` is dx).
template <class F>
void bilinear_walk(const Act& in, const Act& out, F f) {
  const auto ty = taps(in.h, out.h), tx = taps(in.w, out.w);
  for (int n = 0; n < out.n; ++n)
    for (int cb = 0; cb < out.cb(); ++cb)
      for (int i = 0; i < out.h; ++i) {
        const Tap& r = ty[std::size_t(i)];
        for (int j = 0; j < out.w; ++j) {
          const Tap& c = tx[std::size_t(j)];
          const Nbr q{{px(in, n, cb, r.i0, c.i0), px(in, n, cb, r.i0, c.i1), px(in, n, cb, r.i1, c.i0),
                       px(in, n, cb, r.i1, c.i1)}};
          f(q, r.l1, c.l1, px(out, n, cb, i, j));
        }
      }
}

}  // namespace

void avg_pool_forward(const Act& x, int k, const Act& y) {
  check_images(x, y, "avg_pool");
  if (k < 1 || y.h != x.h / k || y.w != x.w / k || y.h < 1 || y.w < 1)
    throw std::invalid_argument("avg_pool " + std::to_string(k) + ": " + std::to_string(x.h) + "x" + std::to_string(x.w) +
                                " does not pool to " + std::to_string(y.h) + "x" + std::to_string(y.w));
  const float inv = 1.f / float(k * k);
  for (int n = 0; n < x.n; ++n)
    for (int cb = 0; cb < x.cb(); ++cb)
      for (int i = 0; i < y.h; ++i)
        for (int j = 0; j < y.w; ++j) {
          float acc[16] = {};
          for (int a = 0; a < k; ++a)
            for (int b = 0; b < k; ++b) {
              const float* s = px(x, n, cb, i * k + a, j * k + b);
              for (int l = 0; l < 16; ++l) acc[l] += s[l];
            }
          float* d = px(y, n, cb, i, j);
          for (int l = 0; l < 16; ++l) d[l] = acc[l] * inv;
        }
}

void avg_pool_backward(const Act& dy, int k, const Act& dx) {
  check_images(dx, dy, "avg_pool backward");
  if (k < 1 || dy.h != dx.h / k || dy.w != dx.w / k) throw std::invalid_argument("avg_pool backward: shapes differ from the forward's");
  std::memset(dx.data, 0, dx.floats() * sizeof(float));
  const float inv = 1.f / float(k * k);
  for (int n = 0; n < dy.n; ++n)
    for (int cb = 0; cb < dy.cb(); ++cb)
      for (int i = 0; i < dy.h; ++i)
        for (int j = 0; j < dy.w; ++j) {
          const float* g = px(dy, n, cb, i, j);
          for (int a = 0; a < k; ++a)
            for (int b = 0; b < k; ++b) {
              float* d = px(dx, n, cb, i * k + a, j * k + b);
              for (int l = 0; l < 16; ++l) d[l] = g[l] * inv;
            }
        }
}

void resize_bilinear_forward(const Act& x, const Act& y) {
  check_images(x, y, "resize_bilinear");
  bilinear_walk(x, y, [](const Nbr& q, float ry, float rx, float* d) {
    for (int l = 0; l < 16; ++l)
      d[l] = (1.f - ry) * ((1.f - rx) * q.p[0][l] + rx * q.p[1][l]) + ry * ((1.f - rx) * q.p[2][l] + rx * q.p[3][l]);
  });
}

void resize_bilinear_backward(const Act& dy, const Act& dx) {
  check_images(dx, dy, "resize_bilinear backward");
  std::memset(dx.data, 0, dx.floats() * sizeof(float));
  bilinear_walk(dx, dy, [](const Nbr& q, float ry, float rx, float* g) {
    for (int l = 0; l < 16; ++l) {
      q.p[0][l] += (1.f - ry) * (1.f - rx) * g[l];
      q.p[1][l] += (1.f - ry) * rx * g[l];
      q.p[2][l] += ry * (1.f - rx) * g[l];
      q.p[3][l] += ry * rx * g[l];
    }
  });
}

}  // namespace yelan::layers
