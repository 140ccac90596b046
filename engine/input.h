// The networks' input path, one for training, `yelan eval` and `yelan run` alike: the TORE
// volume (read out at the sensor's size) averaged down to the config's input, stage 1's
// mask logits cut at probability 0.1, and the input multiplied by that mask. The trainer's
// batches and the streaming pipeline call these and nothing else, so what a network learns
// from is, value for value, what it runs on (tested: tests/test_input_path.cpp).
#pragma once
#include <vector>

#include "camera/repr/tore.h"
#include "layers/buffer.h"

namespace yelan::input {

// Mean of each d x d cell of a volume (C x H x W, channel-major, the sensor's size) into frame
// n of a blocked activation of the model's input size.
void downscale_tore(const std::vector<float>& vol, int sensor_h, int sensor_w, int d, const layers::Act& a, int n);
// The same for the output pixels inside `out_rect` (the input's coordinates, clipped) alone;
// the rest of frame n is left as it was.
void downscale_tore(const std::vector<float>& vol, int sensor_h, int sensor_w, int d, const layers::Act& a, int n,
                    camera::PixelRect out_rect);

// The same straight from the TORE at time t (ToreVolume::readout_mean: no full-size volume in
// between; bit-identical to readout() and downscale_tore()), for the input pixels inside
// `out_rect` alone.
void tore_input(const camera::ToreVolume& tore, std::int64_t t, int d, const layers::Act& a, int n,
                camera::PixelRect out_rect);

// Where yelan run binarises a mask (sigmoid above it: the dancer).
inline constexpr float kMaskCut = 0.1f;

// The binarised mask of channel `channel` of frame n of the mask net's logits (sigmoid > cut),
// one value (0 or 1) per input pixel.
void mask_cut(const layers::Act& logits, int n, int channel, std::vector<float>& keep, float cut = kMaskCut);

// What mask_cut_all says of each channel's mask: its kept pixels and their bounding box
// [x0, x1) x [y0, y1) (all zero for an empty mask).
struct MaskExtent {
  std::size_t kept = 0;
  int x0 = 0, y0 = 0, x1 = 0, y1 = 0;
};

// mask_cut of channels first..C-1 of frame n at once, with each mask's extent: one pass over
// the logits, whose 16 channels of a pixel share a cache line (mask_cut channel by channel
// reads every line once per channel). keep and extent get C entries; those under `first`
// and from `end` on (end < 0: C) are left empty.
void mask_cut_all(const layers::Act& logits, int n, float cut, std::vector<std::vector<float>>& keep,
                  std::vector<MaskExtent>& extent, int first = 0, int end = -1);

// A binarised h x w mask (0 or 1 per pixel) grown by r pixels in every direction: a pixel is
// kept when any pixel of the (2r + 1)-square around it is (a separable running maximum).
void grow_mask(std::vector<float>& keep, int h, int w, int r);

// Frame n of `a` multiplied, every channel, by one value per pixel (inside `r` alone where given).
void apply_mask(const layers::Act& a, int n, const std::vector<float>& keep);
void apply_mask(const layers::Act& a, int n, const std::vector<float>& keep, camera::PixelRect r);

// Stage 2's input from frame n of `a`, whose first channels hold the TORE, behind a binarised
// mask: without `outside`, apply_mask. With it (pose.outside_input: a.c is twice the TORE's
// channels, one block), channels [c, 2c) become the TORE where the mask is not, inside the
// mask's bounding box grown by `margin` pixels and clipped to the frame (the whole frame at
// margin 0: stage 2's crop), zero elsewhere, and channels [0, c) the TORE where it is.
void mask_stage2_input(const layers::Act& a, int n, const std::vector<float>& keep, bool outside, int margin);

}  // namespace yelan::input
