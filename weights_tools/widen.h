// A trained stage 1 carried into a wider U-Net, or a trained stage 2 into a wider ResNet head,
// ConvLSTM and hourglasses, that computes what it computed (up to rounding: the zero terms
// change the order of the sums): every old weight kept in place, the new channels' own
// weights freshly initialised, and every weight that reads a new channel into an old one
// zero. Training then starts from the old net's accuracy instead of from scratch (Net2Net's
// "wider" idea with zeroed fan-out). And the way back for stage 1: its first channels alone.
#pragma once
#include <cstdint>
#include <map>
#include <string>

#include "engine/model_config.h"
#include "weights_tools/weights_file.h"

namespace yelan::weights {

// `old_mask`: a mask group fitting `from`. `to` must differ from `from` only in
// mask.width_mult (at least as wide) and in settings that do not shape the mask net.
// `seed` draws the new channels' weights (MaskNet::init). Throws WeightsError naming
// `source` when the group does not fit `from` or `to` cannot hold it.
std::map<std::string, Tensor> widen_mask_group(const std::map<std::string, Tensor>& old_mask, const ModelConfig& from,
                                               const ModelConfig& to, std::uint64_t seed, const std::string& source);

// The other way for stage 1: a trained mask group cut to `to`'s narrower U-Net, each layer
// keeping its first output channels and each input axis (each part of a concatenation) the
// channels those are: no longer the same outputs (what the dropped channels added is gone),
// but a start for a training at the narrower width that keeps the old net's first features
// rather than drawing them (a narrower stage 1 runs cheaper: 13 against 28 ms a run at width
// 0.25 against 0.375 on one AVX2 core). `to` may change mask.width_mult alone, narrower.
std::map<std::string, Tensor> narrow_mask_group(const std::map<std::string, Tensor>& old_mask, const ModelConfig& from,
                                                const ModelConfig& to, const std::string& source);

// The same for a pose group: `to` may change pose.width_mult and pose.hidden (neither
// narrower) and pose.crop_margin, nothing else of the pose or input sections. The ConvLSTM's
// gates and its concatenated inputs keep each part's old channels at that part's front.
std::map<std::string, Tensor> widen_pose_group(const std::map<std::string, Tensor>& old_pose, const ModelConfig& from,
                                               const ModelConfig& to, std::uint64_t seed, const std::string& source);

}  // namespace yelan::weights
