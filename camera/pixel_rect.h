// A rectangle of pixels, [x0, x1) x [y0, y1): the region a TORE read-out fills, and the box a
// network runs over in model-input pixels (stage 1's crop, stage 2's masked input).
#pragma once
#include <algorithm>

namespace yelan::camera {

struct PixelRect {
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
  bool empty() const { return x1 <= x0 || y1 <= y0; }
  int width() const { return x1 - x0; }
  int height() const { return y1 - y0; }
  // The part inside [0, w) x [0, h) (empty() when none is).
  PixelRect clipped(int w, int h) const { return {std::max(x0, 0), std::max(y0, 0), std::min(x1, w), std::min(y1, h)}; }
};

}  // namespace yelan::camera
