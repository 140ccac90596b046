// Between a weights file and the C++ networks: copy a group into a network's parameters
// (every name and shape checked both ways), collect a network's parameters into a group,
// and PyTorch-style random initialisation with non-trivial BN statistics.
#pragma once
#include <cstdint>
#include <map>
#include <string>

#include "engine/mask_net.h"
#include "engine/model_config.h"
#include "engine/pose_net.h"
#include "layers/param.h"
#include "weights_tools/weights_file.h"

namespace yelan::weights {

// Throws WeightsError listing missing, unexpected and mis-shaped tensors (at most 20 each),
// its message starting with `source` (the weights file's path, where the caller knows it).
// Tensors whose keys start with `may_lack` (non-empty) may be missing from the file: they
// keep their values (a net grown by parts the file's net lacked, e.g. pose.depth_map's
// hourglasses); returns how many did.
std::size_t load_group(const Weights& w, const std::string& group, layers::ParamList& params,
                       const std::string& source = "weights", const std::string& may_lack = "");
std::map<std::string, Tensor> group_of(const layers::ParamList& params);
// BN running statistics and affine parameters drawn away from their defaults (means
// N(0, 0.1), variances U(0.5, 1.5), weights U(0.75, 1.25), biases U(-0.1, 0.1),
// num_batches_tracked U{1..9999}), so that a forward pass depends on every BN tensor.
void randomise_batchnorm(layers::ParamList& params, std::uint64_t seed);

// A weights file's content: the config and both networks' parameters.
Weights weights_of(const ModelConfig& cfg, const layers::ParamList& mask, const layers::ParamList& pose);

// Both networks built from a weights file's config and loaded with its tensors, in
// inference mode (BN with running statistics).
struct LoadedNetworks {
  ModelConfig cfg;
  MaskNet mask;
  PoseNet pose;
  layers::ParamList mp, pp;
  LoadedNetworks(const Weights& w, const std::string& path);
};

}  // namespace yelan::weights
