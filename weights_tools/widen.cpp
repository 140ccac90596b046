#include "weights_tools/widen.h"

#include <regex>

#include "engine/mask_net.h"
#include "weights_tools/network_io.h"
#include "weights_tools/parse_json.h"

namespace yelan::weights {

namespace {

// For each index along one axis of the wider tensor, the old index it holds, or -1 for a
// new channel. A concatenated input (an up block's first conv reads [skip | up-sampled])
// keeps each half's old channels at the front of that half.
std::vector<std::int64_t> axis_map(std::int64_t old_n, std::int64_t new_n, bool two_halves) {
  std::vector<std::int64_t> m(std::size_t(new_n), -1);
  if (!two_halves) {
    for (std::int64_t j = 0; j < old_n; ++j) m[std::size_t(j)] = j;
    return m;
  }
  const std::int64_t ho = old_n / 2, hn = new_n / 2;
  for (std::int64_t j = 0; j < new_n; ++j)
    if (j % hn < ho) m[std::size_t(j)] = (j / hn) * ho + j % hn;
  return m;
}

}  // namespace

std::map<std::string, Tensor> widen_mask_group(const std::map<std::string, Tensor>& old_mask, const ModelConfig& from,
                                               const ModelConfig& to, std::uint64_t seed, const std::string& source) {
  {  // the input section whole, and the mask section but its width (and role, which shapes nothing)
    const auto a = parse_json(from.json), b = parse_json(to.json);
    const auto section = [](const auto& d, const char* key) {
      auto sec = d.contains(key) ? d.at(key) : std::decay_t<decltype(d)>();
      if (sec.is_object()) {
        sec.erase("width_mult");
        sec.erase("role");
      }
      return sec;
    };
    for (const char* key : {"input", "mask"})
      if (section(a, key) != section(b, key))
        throw WeightsError(source + ": widening changes mask.width_mult alone; config '" + to.name + "' also changes its '" +
                           key + "' section");
  }
  if (to.mask_width < from.mask_width)
    throw WeightsError(source + ": config '" + to.name + "' has a narrower mask net (width_mult " + std::to_string(to.mask_width) +
                       " < " + std::to_string(from.mask_width) + "); widening only adds channels");
  {  // the old group must be a whole mask net of `from` (names and shapes, both ways)
    MaskNet old_net(from);
    layers::ParamList op;
    old_net.params(op);
    Weights w;
    w.groups["mask"] = old_mask;
    load_group(w, "mask", op, source);
  }
  MaskNet net(to);
  net.init(seed);
  layers::ParamList np;
  net.params(np);
  std::map<std::string, Tensor> out = group_of(np);
  static const std::regex cat_input(R"(up\d+\.conv\.double_conv\.0\.weight)");
  static const std::regex transposed(R"(up\d+\.up\.weight)");
  for (auto& [name, t] : out) {
    const Tensor& o = old_mask.at(name);
    const std::size_t dims = t.shape.size();
    if (dims == 0) {
      t.data = o.data;
      continue;
    }
    // Which axis holds the output channels, which the input channels (PyTorch's layouts).
    const bool is_transposed = std::regex_match(name, transposed);
    const std::size_t out_axis = is_transposed ? 1 : 0, in_axis = dims >= 2 ? (is_transposed ? 0 : 1) : dims;
    std::vector<std::vector<std::int64_t>> maps(dims);
    for (std::size_t a = 0; a < dims; ++a) {
      const bool halves = a == in_axis && std::regex_match(name, cat_input);
      if (t.shape[a] < o.shape[a] || (a >= 2 && t.shape[a] != o.shape[a]) || (halves && (t.shape[a] % 2 || o.shape[a] % 2)))
        throw WeightsError(source + ": mask/" + name + " " + shape_text(o.shape) + " does not widen to " + shape_text(t.shape));
      maps[a] = axis_map(o.shape[a], t.shape[a], halves);
    }
    std::vector<std::int64_t> idx(dims, 0);
    for (std::size_t e = 0; e < t.data.size(); ++e) {
      bool out_old = maps[out_axis][std::size_t(idx[out_axis])] >= 0, all_old = out_old;
      std::int64_t oe = 0;
      for (std::size_t a = 0; a < dims; ++a) {
        const std::int64_t m = maps[a][std::size_t(idx[a])];
        all_old = all_old && m >= 0;
        oe = oe * o.shape[a] + (m < 0 ? 0 : m);
      }
      if (all_old)
        t.data[e] = o.data[std::size_t(oe)];
      else if (out_old)
        t.data[e] = 0;  // a new channel read into an old one: zero, so the output is unchanged
      for (std::size_t a = dims; a-- > 0;) {  // next index, last axis fastest
        if (++idx[a] < t.shape[a]) break;
        idx[a] = 0;
      }
    }
  }
  return out;
}

}  // namespace yelan::weights
