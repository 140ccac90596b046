// The networks' input path, one for training, `yelan eval` and `yelan run` alike: the TORE
// volume (read out at the sensor's size) averaged down to the config's input, stage 1's
// mask logits cut at probability 0.1, and the input multiplied by that mask. The trainer's
// batches and the streaming pipeline call these and nothing else, so what a network learns
// from is, value for value, what it runs on (tested: tests/test_input_path.cpp).
#pragma once
#include <vector>

#include "layers/buffer.h"

namespace yelan::input {

// Mean of each d x d cell of a volume (C x H x W, channel-major, the sensor's size) into frame
// n of a blocked activation of the model's input size.
void downscale_tore(const std::vector<float>& vol, int sensor_h, int sensor_w, int d, const layers::Act& a, int n);

// Where yelan run binarises a mask (sigmoid above it: the dancer).
inline constexpr float kMaskCut = 0.1f;

// The binarised mask of channel `channel` of frame n of the mask net's logits (sigmoid > cut),
// one value (0 or 1) per input pixel.
void mask_cut(const layers::Act& logits, int n, int channel, std::vector<float>& keep, float cut = kMaskCut);

// Frame n of `a` multiplied, every channel, by one value per pixel.
void apply_mask(const layers::Act& a, int n, const std::vector<float>& keep);

}  // namespace yelan::input
