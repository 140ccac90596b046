// Stage 1's mask against the true mask, counted at the net's size: the IoU, and the IoU off
// the true silhouette's edge. The second says whether what the IoU loses is a band around the
// outline (a cell either way at the edge: resolution, a trail behind a moving limb) or whole
// regions (a missed arm, a filled gap, a curtain taken for a dancer). A third count takes
// every sensor pixel against its cell instead of each cell's centre pixel against the cell:
// the IoU a user of the mask at the sensor's size sees, free of where in its cell the centre
// sample falls (at a downscale of 2 it is the cell's lower right pixel, while the training
// labels call a cell the dancer's when at least half its pixels are).
#pragma once
#include <cstdint>
#include <map>
#include <string>

namespace yelan::train {

struct MaskOverlap {
  double inter = 0, uni = 0;                    // every cell
  double inter_off_edge = 0, uni_off_edge = 0;  // cells whose 3 x 3 neighbourhood of truth is all one class
  double inter_px = 0, uni_px = 0;              // sensor pixels, each with its cell's verdict
  double iou() const { return uni > 0 ? inter / uni : 0; }
  double iou_off_edge() const { return uni_off_edge > 0 ? inter_off_edge / uni_off_edge : 0; }
  double iou_px() const { return uni_px > 0 ? inter_px / uni_px : 0; }
  MaskOverlap& operator+=(const MaskOverlap& o);
  MaskOverlap operator-(const MaskOverlap& o) const;
};

// truth: the sensor's mask (sensor_w wide, nonzero = dancer), sampled at each cell's centre
// (y * down + down / 2, x * down + down / 2); keep: the net's mask at mask_h x mask_w, > 0 = dancer.
// The pixel count covers the sensor's first mask_h * down rows and mask_w * down columns.
void add_mask_overlap(MaskOverlap& m, const std::uint8_t* truth, int sensor_w, const float* keep, int mask_h,
                      int mask_w, int down);

// The IoU of each key whose frames have one (a true or a kept pixel; at the sensor's pixels
// with sensor_px): a key with neither, such as a dancer wholly behind furniture all along,
// is left out rather than scored 0, which would read as a mask that missed the dancer.
std::map<std::string, double> measured_iou(const std::map<std::string, MaskOverlap>& by_key, bool sensor_px = false);

}  // namespace yelan::train
