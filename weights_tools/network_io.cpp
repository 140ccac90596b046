#include "weights_tools/network_io.h"

#include <random>
#include <set>

namespace yelan::weights {
namespace {
bool ends_with(const std::string& s, const std::string& tail) {
  return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}
}  // namespace

std::size_t load_group(const Weights& w, const std::string& group, layers::ParamList& params, const std::string& source,
                       const std::string& may_lack) {
  auto g = w.groups.find(group);
  if (g == w.groups.end()) throw WeightsError(source + ": no group /" + group);
  std::vector<std::string> missing, shape, extra;
  std::set<std::string> ours;
  for (auto& p : params) {
    ours.insert(p.key);
    auto it = g->second.find(p.key);
    if (it == g->second.end()) {
      if (!may_lack.empty() && p.key.rfind(may_lack, 0) == 0) continue;
      missing.push_back(p.key);
    } else if (it->second.shape != p.param->shape) {
      shape.push_back(p.key + " is " + shape_text(it->second.shape) + ", the network needs " + shape_text(p.param->shape));
    }
  }
  for (auto& [k, t] : g->second)
    if (!ours.count(k)) extra.push_back(k);
  if (!missing.empty() || !shape.empty() || !extra.empty()) {
    std::string msg = source + ": /" + group + " does not fit the network built from its config";
    auto list = [&](const char* what, const std::vector<std::string>& v) {
      for (std::size_t i = 0; i < v.size() && i < 20; ++i) msg += std::string("\n  ") + what + v[i];
      if (v.size() > 20) msg += "\n  ... and " + std::to_string(v.size() - 20) + " more " + what;
    };
    list("missing: ", missing);
    list("unexpected: ", extra);
    list("mis-shaped: ", shape);
    throw WeightsError(msg);
  }
  std::size_t kept = 0;
  for (auto& p : params) {
    const auto it = g->second.find(p.key);
    if (it == g->second.end()) {
      ++kept;
      continue;
    }
    std::copy(it->second.data.begin(), it->second.data.end(), p.param->value.data());
  }
  return kept;
}

std::map<std::string, Tensor> group_of(const layers::ParamList& params) {
  std::map<std::string, Tensor> out;
  for (const auto& p : params) {
    Tensor t;
    t.shape = p.param->shape;
    t.data.assign(p.param->value.data(), p.param->value.data() + p.param->numel());
    out[p.key] = std::move(t);
  }
  return out;
}

void randomise_batchnorm(layers::ParamList& params, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<float> mean(0.f, 0.1f);
  std::uniform_real_distribution<float> var(0.5f, 1.5f), w(0.75f, 1.25f), b(-0.1f, 0.1f);
  std::uniform_int_distribution<int> count(1, 9999);
  // BN tensors come in fives ending .weight .bias .running_mean .running_var
  // .num_batches_tracked; a conv's .weight is recognised by not having running stats beside it.
  std::set<std::string> bn_prefixes;
  for (auto& p : params)
    if (ends_with(p.key, ".running_mean")) bn_prefixes.insert(p.key.substr(0, p.key.size() - 12));
  for (auto& p : params) {
    const auto dot = p.key.rfind('.');
    if (dot == std::string::npos || !bn_prefixes.count(p.key.substr(0, dot))) continue;
    const std::string leaf = p.key.substr(dot + 1);
    for (std::size_t i = 0; i < p.param->numel(); ++i) {
      float& v = p.param->value[i];
      if (leaf == "running_mean") v = mean(rng);
      else if (leaf == "running_var") v = var(rng);
      else if (leaf == "weight") v = w(rng);
      else if (leaf == "bias") v = b(rng);
      else if (leaf == "num_batches_tracked") v = float(count(rng));
    }
  }
}

Weights weights_of(const ModelConfig& cfg, const layers::ParamList& mask, const layers::ParamList& pose) {
  Weights w;
  w.config_json = cfg.json;
  w.groups["mask"] = group_of(mask);
  w.groups["pose"] = group_of(pose);
  return w;
}

LoadedNetworks::LoadedNetworks(const Weights& w, const std::string& path)
    : cfg(parse_model_config(w.config_json, path + ": attribute config")), mask(cfg), pose(cfg) {
  mask.params(mp);
  pose.params(pp);
  load_group(w, "mask", mp, path);
  load_group(w, "pose", pp, path);
  mask.weights_changed();
  pose.weights_changed();
  mask.set_training(false);
  pose.set_training(false);
}

}  // namespace yelan::weights
