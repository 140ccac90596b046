// Heatmap heads on the blocked layout (`planes` = N x CB planes of H x W pixels, 16 joint
// lanes each): the flat spatial softmax of every joint map and DSNT, the expectation of
// pixel-centre coordinates linspace(-(n-1)/n, (n-1)/n, n) under it (SPEC section 5).
#pragma once
#include <cstddef>

#include "kernels/cpu.h"

namespace yelan::kernels {

struct HeatmapKernels {
  Isa isa;
  void (*softmax_fwd)(int planes, std::size_t pixels, const float* x, float* y);
  // dx = y * (dy - sum(y * dy)) per lane
  void (*softmax_bwd)(int planes, std::size_t pixels, const float* y, const float* dy, float* dx);
  // out [planes][2][16]: expected x (width) then y (height) coordinate of each lane
  void (*dsnt_fwd)(int planes, int h, int w, const float* y, float* out);
  // dy = dout_x * x_coord(w) + dout_y * y_coord(h); overwrites dy
  void (*dsnt_bwd)(int planes, int h, int w, const float* dout, float* dy);
};

const HeatmapKernels& heatmap_kernels(Isa isa);
inline const HeatmapKernels& heatmap_kernels() { return heatmap_kernels(active_isa()); }
extern const HeatmapKernels heatmap_scalar;

inline float dsnt_coordinate(int i, int n) { return (2.f * float(i) + 1.f) / float(n) - 1.f; }

}  // namespace yelan::kernels
