#include "weights_tools/widen.h"

#include <functional>
#include <regex>

#include "engine/mask_net.h"
#include "engine/pose_net.h"
#include "weights_tools/network_io.h"
#include "weights_tools/parse_json.h"

namespace yelan::weights {

namespace {

// An axis that concatenates parts (a ConvLSTM's [input | hidden], its four gates, a U-Net
// block's [skip | up-sampled]) keeps each part's old channels at the front of that part.
using Parts = std::vector<std::int64_t>;

// How one tensor's axes widen: which axis holds the output channels and which the input
// channels (PyTorch's layouts), and the parts of each (empty: the whole axis is one part).
struct Layout {
  bool transposed = false;
  Parts out_old, out_new, in_old, in_new;
};
using LayoutOf = std::function<Layout(const std::string& name)>;

// For each index along the new axis, the old index it holds, or -1 for a new channel. Each
// part keeps its first channels: all of them when widening, as many as fit when narrowing.
std::vector<std::int64_t> axis_map(Parts old_parts, Parts new_parts, std::int64_t old_n, std::int64_t new_n, bool narrow,
                                   bool* fits) {
  if (old_parts.empty()) old_parts = {old_n}, new_parts = {new_n};
  std::int64_t so = 0, sn = 0;
  for (std::size_t i = 0; i < old_parts.size(); ++i) so += old_parts[i], sn += new_parts[i];
  *fits = so == old_n && sn == new_n;
  std::vector<std::int64_t> m(std::size_t(std::max<std::int64_t>(new_n, 0)), -1);
  if (!*fits) return m;
  std::int64_t o0 = 0, n0 = 0;
  for (std::size_t i = 0; i < old_parts.size(); ++i) {
    if (narrow ? new_parts[i] > old_parts[i] : new_parts[i] < old_parts[i]) *fits = false;
    for (std::int64_t j = 0; j < std::min(old_parts[i], new_parts[i]); ++j) m[std::size_t(n0 + j)] = o0 + j;
    o0 += old_parts[i];
    n0 += new_parts[i];
  }
  return m;
}

// `out` holds the new net's freshly initialised tensors; every old weight it has room for is put
// in its place and every weight reading a new channel into an old one is zeroed (narrowing:
// every new channel is an old one, and the old ones past each part's new size are dropped).
void carry_over(const std::map<std::string, Tensor>& old, std::map<std::string, Tensor>& out, const LayoutOf& layout_of,
                const std::string& group, const std::string& source, bool narrow = false) {
  for (auto& [name, t] : out) {
    const Tensor& o = old.at(name);
    const std::size_t dims = t.shape.size();
    if (dims == 0) {
      t.data = o.data;
      continue;
    }
    const Layout l = layout_of(name);
    const std::size_t out_axis = l.transposed ? 1 : 0, in_axis = dims >= 2 ? (l.transposed ? 0 : 1) : dims;
    std::vector<std::vector<std::int64_t>> maps(dims);
    for (std::size_t a = 0; a < dims; ++a) {
      bool fits = o.shape.size() == dims && (narrow ? t.shape[a] <= o.shape[a] : t.shape[a] >= o.shape[a]) &&
                  (a < 2 || t.shape[a] == o.shape[a]);
      if (fits) {
        const bool is_out = a == out_axis, is_in = a == in_axis;
        maps[a] = axis_map(is_out ? l.out_old : is_in ? l.in_old : Parts{}, is_out ? l.out_new : is_in ? l.in_new : Parts{},
                           o.shape[a], t.shape[a], narrow, &fits);
      }
      if (!fits)
        throw WeightsError(source + ": " + group + "/" + name + " " + shape_text(o.shape) + " does not " +
                           (narrow ? "narrow" : "widen") + " to " + shape_text(t.shape));
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
}

// `to` may change nothing of the input section, and of `section` only the keys in `free`.
void check_sections(const ModelConfig& from, const ModelConfig& to, const char* section, std::initializer_list<const char*> free,
                    const std::string& what, const std::string& source, const char* verb = "widening") {
  const auto a = parse_json(from.json), b = parse_json(to.json);
  const auto cut = [&](const auto& d, const char* key) {
    auto sec = d.contains(key) ? d.at(key) : std::decay_t<decltype(d)>();
    if (sec.is_object() && std::string(key) == section)
      for (const char* k : free) sec.erase(k);
    return sec;
  };
  for (const char* key : {"input", section})
    if (cut(a, key) != cut(b, key))
      throw WeightsError(source + ": " + verb + " changes " + what + " alone; config '" + to.name + "' also changes its '" + key +
                         "' section");
}

// The old group must be a whole net of `from` (names and shapes, both ways).
template <class Net>
void check_fits(const std::map<std::string, Tensor>& group, const char* name, const ModelConfig& from, const std::string& source) {
  Net old_net(from);
  layers::ParamList op;
  old_net.params(op);
  Weights w;
  w.groups[name] = group;
  load_group(w, name, op, source);
}

template <class Net>
std::map<std::string, Tensor> fresh_group(const ModelConfig& to, std::uint64_t seed) {
  Net net(to);
  net.init(seed);
  layers::ParamList np;
  net.params(np);
  return group_of(np);
}

// The U-Net's axes: the up-sampling's transposed weights, and each up block's first
// convolution reading [skip | up-sampled], each part the level's width.
LayoutOf mask_layout(const std::map<std::string, Tensor>& old_mask, const std::map<std::string, Tensor>& out) {
  return [&](const std::string& name) {
    static const std::regex cat_input(R"(up\d+\.conv\.double_conv\.0\.weight)");
    static const std::regex transposed(R"(up\d+\.up\.weight)");
    Layout l;
    l.transposed = std::regex_match(name, transposed);
    if (std::regex_match(name, cat_input)) {
      // An odd width is not two halves: the parts then miss the axis, which carry_over refuses.
      const std::int64_t o = old_mask.at(name).shape.at(1), n = out.at(name).shape.at(1);
      l.in_old = {o / 2, o / 2};
      l.in_new = {n / 2, n / 2};
    }
    return l;
  };
}

}  // namespace

std::map<std::string, Tensor> widen_mask_group(const std::map<std::string, Tensor>& old_mask, const ModelConfig& from,
                                               const ModelConfig& to, std::uint64_t seed, const std::string& source) {
  check_sections(from, to, "mask", {"width_mult", "role"}, "mask.width_mult", source);  // role shapes nothing
  if (to.mask_width < from.mask_width)
    throw WeightsError(source + ": config '" + to.name + "' has a narrower mask net (width_mult " + std::to_string(to.mask_width) +
                       " < " + std::to_string(from.mask_width) + "); widening only adds channels");
  check_fits<MaskNet>(old_mask, "mask", from, source);
  std::map<std::string, Tensor> out = fresh_group<MaskNet>(to, seed);
  carry_over(old_mask, out, mask_layout(old_mask, out), "mask", source);
  return out;
}

std::map<std::string, Tensor> narrow_mask_group(const std::map<std::string, Tensor>& old_mask, const ModelConfig& from,
                                                const ModelConfig& to, const std::string& source) {
  check_sections(from, to, "mask", {"width_mult", "role"}, "mask.width_mult", source, "narrowing");
  if (to.mask_width >= from.mask_width)
    throw WeightsError(source + ": config '" + to.name + "' has no narrower mask net (width_mult " + std::to_string(to.mask_width) +
                       " >= " + std::to_string(from.mask_width) + "); narrowing only drops channels");
  check_fits<MaskNet>(old_mask, "mask", from, source);
  std::map<std::string, Tensor> out = fresh_group<MaskNet>(to, 0);  // the shapes: every value is an old one
  carry_over(old_mask, out, mask_layout(old_mask, out), "mask", source, true);
  return out;
}

std::map<std::string, Tensor> widen_pose_group(const std::map<std::string, Tensor>& old_pose, const ModelConfig& from,
                                               const ModelConfig& to, std::uint64_t seed, const std::string& source) {
  // pose.outside_input adds input channels (the events outside the mask) read by zero weights.
  check_sections(from, to, "pose", {"width_mult", "hidden", "crop_margin", "outside_input"},
                 "pose.width_mult, pose.hidden and pose.outside_input", source);
  if (from.outside_input && !to.outside_input)
    throw WeightsError(source + ": config '" + to.name + "' drops pose.outside_input; widening only adds channels");
  if (to.pose_width < from.pose_width || to.hidden < from.hidden)
    throw WeightsError(source + ": config '" + to.name + "' has a narrower pose net (width_mult " + std::to_string(to.pose_width) +
                       ", hidden " + std::to_string(to.hidden) + " against " + std::to_string(from.pose_width) + ", " +
                       std::to_string(from.hidden) + "); widening only adds channels");
  check_fits<PoseNet>(old_pose, "pose", from, source);
  std::map<std::string, Tensor> out = fresh_group<PoseNet>(to, seed);
  const std::int64_t mid_o = from.resnet_mid(), mid_n = to.resnet_mid(), hid_o = from.hidden, hid_n = to.hidden;
  // The hourglasses' up-sampling block: a transposed 3x3 and a transposed 1x1 shortcut.
  static const std::regex transposed(R"((xy|zy|xz)_hm_cnns\.\d+\.up_layers\.2\.(module|shortcut)\.0\.weight)");
  const LayoutOf layout = [&](const std::string& name) {
    Layout l;
    l.transposed = std::regex_match(name, transposed);
    if (name == "cl.cell_list.0.conv.weight" || name == "cl.cell_list.0.conv.bias") {
      l.out_old = Parts(4, hid_o);  // the gates, a block of hidden channels each
      l.out_new = Parts(4, hid_n);
      l.in_old = {mid_o, hid_o};    // [the head's features | the hidden state]
      l.in_new = {mid_n, hid_n};
    } else if (name == "cl.fuse_list.0.weight" && from.bidirectional) {
      l.in_old = {hid_o, hid_o};  // [forward | backward]
      l.in_new = {hid_n, hid_n};
    } else if (from.convlstm && (name == "cl_skip_block.module.0.weight" || name == "cl_skip_block.shortcut.0.weight")) {
      l.in_old = {mid_o, hid_o};  // [the head's features | the ConvLSTM's output]
      l.in_new = {mid_n, hid_n};
    }
    return l;
  };
  carry_over(old_pose, out, layout, "pose", source);
  return out;
}

}  // namespace yelan::weights
