#include "kernels/heatmap.h"

#include <cmath>

#include "kernels/dispatch.h"

namespace yelan::kernels {
namespace {

constexpr int L = 16;

void softmax_fwd(int planes, std::size_t pixels, const float* x, float* y) {
  for (int p = 0; p < planes; ++p)
    for (int l = 0; l < L; ++l) {
      auto at = [&](std::size_t i) { return (std::size_t(p) * pixels + i) * L + l; };
      float m = x[at(0)];
      for (std::size_t i = 1; i < pixels; ++i) m = std::max(m, x[at(i)]);
      double s = 0;
      for (std::size_t i = 0; i < pixels; ++i) s += std::exp(double(x[at(i)]) - m);
      for (std::size_t i = 0; i < pixels; ++i) y[at(i)] = float(std::exp(double(x[at(i)]) - m) / s);
    }
}

void softmax_bwd(int planes, std::size_t pixels, const float* y, const float* dy, float* dx) {
  for (int p = 0; p < planes; ++p)
    for (int l = 0; l < L; ++l) {
      auto at = [&](std::size_t i) { return (std::size_t(p) * pixels + i) * L + l; };
      double dot = 0;
      for (std::size_t i = 0; i < pixels; ++i) dot += double(y[at(i)]) * dy[at(i)];
      for (std::size_t i = 0; i < pixels; ++i) dx[at(i)] = float(y[at(i)] * (dy[at(i)] - dot));
    }
}

void dsnt_fwd(int planes, int h, int w, const float* y, float* out) {
  for (int p = 0; p < planes; ++p)
    for (int l = 0; l < L; ++l) {
      double ex = 0, ey = 0;
      for (int r = 0; r < h; ++r)
        for (int c = 0; c < w; ++c) {
          const double v = y[((std::size_t(p) * h + r) * w + c) * L + l];
          ex += v * dsnt_coordinate(c, w);
          ey += v * dsnt_coordinate(r, h);
        }
      out[(p * 2 + 0) * L + l] = float(ex);
      out[(p * 2 + 1) * L + l] = float(ey);
    }
}

void dsnt_bwd(int planes, int h, int w, const float* dout, float* dy) {
  for (int p = 0; p < planes; ++p)
    for (int r = 0; r < h; ++r)
      for (int c = 0; c < w; ++c)
        for (int l = 0; l < L; ++l)
          dy[((std::size_t(p) * h + r) * w + c) * L + l] =
              dout[(p * 2 + 0) * L + l] * dsnt_coordinate(c, w) + dout[(p * 2 + 1) * L + l] * dsnt_coordinate(r, h);
}

}  // namespace

const HeatmapKernels heatmap_scalar{Isa::scalar, softmax_fwd, softmax_bwd, dsnt_fwd, dsnt_bwd};
YELAN_KERNEL_DISPATCH(HeatmapKernels, heatmap)

}  // namespace yelan::kernels
