// Resampling between resolutions, for a stage 1 that runs on fewer pixels than stage 2 reads
// (mask.pool): k x k average pooling (stride k, PyTorch's avg_pool2d: the last partial row
// and column dropped) and bilinear resizing to any size (F.interpolate, mode 'bilinear',
// align_corners False). Both are linear; each backward is the forward's adjoint.
#pragma once
#include "layers/param.h"

namespace yelan::layers {

// y: x.h / k x x.w / k.
void avg_pool_forward(const Act& x, int k, const Act& y);
void avg_pool_backward(const Act& dy, int k, const Act& dx);  // overwrites dx, the dropped edge zero

// y: any size; y's pixel (i, j) samples x at ((i + 0.5) x.h / y.h - 0.5, likewise j), clamped
// at 0 and the last row and column.
void resize_bilinear_forward(const Act& x, const Act& y);
void resize_bilinear_backward(const Act& dy, const Act& dx);  // overwrites dx

}  // namespace yelan::layers
