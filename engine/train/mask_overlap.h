// Stage 1's mask against the true mask, counted at the net's size: the IoU, and the IoU off
// the true silhouette's edge. The second says whether what the IoU loses is a band around the
// outline (a cell either way at the edge: resolution, a trail behind a moving limb) or whole
// regions (a missed arm, a filled gap, a curtain taken for a dancer).
#pragma once
#include <cstdint>

namespace yelan::train {

struct MaskOverlap {
  double inter = 0, uni = 0;                    // every cell
  double inter_off_edge = 0, uni_off_edge = 0;  // cells whose 3 x 3 neighbourhood of truth is all one class
  double iou() const { return uni > 0 ? inter / uni : 0; }
  double iou_off_edge() const { return uni_off_edge > 0 ? inter_off_edge / uni_off_edge : 0; }
  MaskOverlap& operator+=(const MaskOverlap& o);
  MaskOverlap operator-(const MaskOverlap& o) const;
};

// truth: the sensor's mask (sensor_w wide, nonzero = dancer), sampled at each cell's centre
// (y * down + down / 2, x * down + down / 2); keep: the net's mask at mask_h x mask_w, > 0 = dancer.
void add_mask_overlap(MaskOverlap& m, const std::uint8_t* truth, int sensor_w, const float* keep, int mask_h,
                      int mask_w, int down);

}  // namespace yelan::train
