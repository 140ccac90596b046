// `yelan model summary|forward` and `yelan weights init`: the C++ networks from a config
// or a weights file.
#include <filesystem>
#include <hdf5.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <iomanip>
#include <map>
#include <sstream>

#include "camera/io/h5.h"
#include "camera/io/temp_file.h"
#include "engine/cli/args.h"
#include "engine/cli/cli.h"
#include "engine/cli/handlers.h"
#include "engine/cli/output_path.h"
#include "engine/mask_net.h"
#include "engine/pose_net.h"
#include "layers/conv2d.h"
#include "weights_tools/network_io.h"

namespace yelan::cli {
namespace {

namespace h5 = camera::h5;

std::int64_t count(const layers::ParamList& params, bool trainable_only) {
  std::int64_t n = 0;
  for (const auto& p : params)
    if (!trainable_only || p.param->trainable) n += std::int64_t(p.param->numel());
  return n;
}

// Parameters per top-level module (the key's first component), in first-seen order.
std::vector<std::pair<std::string, std::int64_t>> by_module(const layers::ParamList& params) {
  std::vector<std::pair<std::string, std::int64_t>> out;
  for (const auto& p : params) {
    if (!p.param->trainable) continue;
    const std::string top = p.key.substr(0, p.key.find('.'));
    if (out.empty() || out.back().first != top) out.push_back({top, 0});
    out.back().second += std::int64_t(p.param->numel());
  }
  return out;
}

// Blocked activation <-> NCHW float array.
void to_blocked(const std::vector<float>& a, const layers::Act& o) {
  for (int n = 0; n < o.n; ++n)
    for (int c = 0; c < o.c; ++c)
      for (std::size_t p = 0; p < o.pixels(); ++p)
        o.data[((std::size_t(n) * o.cb() + c / 16) * o.pixels() + p) * 16 + c % 16] = a[(std::size_t(n) * o.c + c) * o.pixels() + p];
}
std::vector<float> from_blocked(const layers::Act& o) {
  std::vector<float> a(std::size_t(o.n) * o.c * o.pixels());
  for (int n = 0; n < o.n; ++n)
    for (int c = 0; c < o.c; ++c)
      for (std::size_t p = 0; p < o.pixels(); ++p)
        a[(std::size_t(n) * o.c + c) * o.pixels() + p] = o.data[((std::size_t(n) * o.cb() + c / 16) * o.pixels() + p) * 16 + c % 16];
  return a;
}

void write_dataset(hid_t file, const std::string& name, const std::vector<hsize_t>& dims, const float* data) {
  // intermediate groups ("heatmaps/stage0/xy")
  for (std::size_t at = name.find('/'); at != std::string::npos; at = name.find('/', at + 1))
    if (!h5::exists(file, name.substr(0, at))) h5::create_group(file, name.substr(0, at));
  h5::H5Id space = h5::check(H5Screate_simple(int(dims.size()), dims.data(), nullptr), "dataspace for " + name);
  h5::H5Id props = h5::untimed_dataset_props();
  h5::H5Id ds = h5::check(H5Dcreate2(file, name.c_str(), H5T_NATIVE_FLOAT, space.get(), H5P_DEFAULT, props.get(), H5P_DEFAULT),
                          "create " + name);
  h5::check(H5Dwrite(ds.get(), H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), "write " + name);
}

// One row of the per-layer table: a convolution, with BN/ReLU folded into it as inference
// runs it, named by its state_dict key.
struct LayerRow {
  std::string net, name;
  layers::ConvRecord rec;
  std::int64_t params;
  std::uint64_t act_bytes;  // the output as we hold it (channels padded to blocks of 16)
};

std::vector<LayerRow> layer_rows(const char* net, const std::vector<layers::ConvRecord>& trace,
                                 const layers::ParamList& params) {
  std::map<const layers::Param*, std::string> key_of;
  std::map<std::string, std::int64_t> numel_of;
  for (const auto& p : params) {
    key_of[p.param] = p.key;
    numel_of[p.key] = std::int64_t(p.param->numel());
  }
  std::vector<LayerRow> rows;
  for (const auto& r : trace) {
    std::string key = key_of.count(r.weight) ? key_of[r.weight] : "?";
    const std::string name = key.size() > 7 && key.ends_with(".weight") ? key.substr(0, key.size() - 7) : key;
    const std::int64_t n = numel_of[key] + (numel_of.count(name + ".bias") ? numel_of[name + ".bias"] : 0);
    rows.push_back({net, name, r, n, std::uint64_t((r.out_c + 15) / 16) * 16 * r.out_h * r.out_w * 4});
  }
  return rows;
}

std::string shape_str(int c, int h, int w) { return std::to_string(c) + "x" + std::to_string(h) + "x" + std::to_string(w); }

int summary(const Args& a, std::ostream& out) {
  a.expect_positionals(0, 0);
  const auto name = a.value("--config");
  if (!name) throw UsageError("model summary needs --config NAME|FILE");
  const ModelConfig cfg = load_model_config(*name);
  MaskNet mask(cfg);
  PoseNet pose(cfg);
  layers::ParamList mp, pp;
  mask.params(mp);
  pose.params(pp);
  // A forward of one zero frame (a window of 1) through both networks, as inference runs it,
  // tracing every convolution; per-frame work does not depend on the window length.
  // With pose.outside_input stage 2 reads twice the channels; stage 1 the first ones of the same block.
  layers::Floats input(std::size_t((cfg.pose_channels() + 15) / 16) * cfg.height() * cfg.width() * 16);
  const layers::Act x{input.data(), 1, cfg.channels, cfg.height(), cfg.width()};
  const layers::Act x_pose{input.data(), 1, cfg.pose_channels(), cfg.height(), cfg.width()};
  mask.set_training(false);
  pose.set_training(false);
  layers::NoGrad no_grad;
  std::vector<layers::ConvRecord> mask_trace, pose_trace;
  const std::size_t held = layers::floats_live_bytes();
  layers::reset_floats_peak();
  layers::conv_trace() = &mask_trace;
  mask.forward(x);
  layers::conv_trace() = &pose_trace;
  pose.forward(x_pose, 1);
  layers::conv_trace() = nullptr;
  const std::size_t peak = layers::floats_peak_bytes() - held;
  std::vector<LayerRow> rows = layer_rows("mask", mask_trace, mp), pose_rows = layer_rows("pose", pose_trace, pp);
  rows.insert(rows.end(), pose_rows.begin(), pose_rows.end());
  double flops[2] = {0, 0};
  std::uint64_t act[2] = {0, 0};
  for (const auto& r : rows) {
    flops[r.net == "pose"] += double(r.rec.flops);
    act[r.net == "pose"] += r.act_bytes;
  }
  if (a.flag("--json")) {
    out << "{\"config\": \"" << cfg.name << "\", \"params_mask\": " << count(mp, true) << ", \"params_pose\": "
        << count(pp, true) << ", \"flops_per_pose\": " << std::llround(flops[1])
        << ", \"flops_per_mask\": " << std::llround(flops[0]) << ", \"activation_bytes_mask\": " << act[0]
        << ", \"activation_bytes_pose\": " << act[1] << ", \"peak_bytes_inference\": " << peak << ", \"input\": ["
        << cfg.window << ", " << cfg.channels << ", " << cfg.height() << ", " << cfg.width() << "], \"layers\": [";
    for (std::size_t i = 0; i < rows.size(); ++i) {
      const auto& r = rows[i];
      out << (i ? ", " : "") << "{\"net\": \"" << r.net << "\", \"name\": \"" << r.name << "\", \"type\": \""
          << (r.rec.transposed ? "deconv" : "conv") << r.rec.k << "x" << r.rec.k << "/" << r.rec.stride
          << "\", \"in\": [" << r.rec.in_c << ", " << r.rec.in_h << ", " << r.rec.in_w << "], \"out\": [" << r.rec.out_c
          << ", " << r.rec.out_h << ", " << r.rec.out_w << "], \"params\": " << r.params << ", \"flops\": " << r.rec.flops
          << ", \"act_bytes\": " << r.act_bytes << "}";
    }
    out << "], \"modules\": [";
    bool first = true;
    for (auto [net, params] : {std::pair{"mask", &mp}, std::pair{"pose", &pp}})
      for (auto& [m, n] : by_module(*params)) {
        out << (first ? "" : ", ") << "{\"net\": \"" << net << "\", \"module\": \"" << m << "\", \"params\": " << n << "}";
        first = false;
      }
    out << "]}\n";
    return kOk;
  }
  out << "config " << cfg.name << ": input " << cfg.window << " x " << cfg.channels << " x " << cfg.height() << " x "
      << cfg.width() << ", ConvLSTM " << (cfg.bidirectional ? "bidirectional" : "causal") << "\n";
  if (cfg.outside_input)
    out << "stage 2 reads " << cfg.pose_channels() << " channels: the input inside stage 1's mask, then outside it (pose.outside_input)\n";
  if (cfg.mask_pool > 1)
    out << "stage 1 on the input average-pooled " << cfg.mask_pool << " x " << cfg.mask_pool << " ("
        << cfg.height() / cfg.mask_pool << " x " << cfg.width() / cfg.mask_pool
        << "), its mask logits resized back bilinearly\n";
  if (cfg.mask_crop_margin > 0)
    out << "stage 1, while a dancer is there, over its last masks' box grown by " << cfg.mask_crop_margin
        << " input pixels (mask.crop_margin): the rows below are its whole-frame runs\n";
  if (cfg.mask_mirror)
    out << "stage 1 runs twice a frame, on the input and on its mirror image, the two averaged (run.mask_mirror): its layers are listed twice\n";
  out << "per frame, as inference runs it (BN and ReLU folded into each convolution):\n";
  out << std::left << std::setw(5) << "net" << std::setw(42) << "layer" << std::setw(13) << "op" << std::setw(14)
      << "in" << std::setw(14) << "out" << std::right << std::setw(10) << "params" << std::setw(10) << "MFLOPs"
      << std::setw(10) << "act KiB" << "\n";
  for (const auto& r : rows) {
    std::ostringstream op;
    op << (r.rec.transposed ? "deconv" : "conv") << r.rec.k << "x" << r.rec.k << "/" << r.rec.stride;
    out << std::left << std::setw(5) << r.net << std::setw(42) << r.name << std::setw(13) << op.str() << std::setw(14)
        << shape_str(r.rec.in_c, r.rec.in_h, r.rec.in_w) << std::setw(14) << shape_str(r.rec.out_c, r.rec.out_h, r.rec.out_w)
        << std::right << std::setw(10) << r.params << std::setw(10) << std::fixed << std::setprecision(1)
        << double(r.rec.flops) / 1e6 << std::setw(10) << r.act_bytes / 1024 << "\n";
  }
  for (auto [net, params] : {std::pair{"mask", &mp}, std::pair{"pose", &pp}}) {
    out << net << " net: " << count(*params, true) << " parameters (+" << count(*params, false) - count(*params, true)
        << " BN buffers)\n";
    for (auto& [m, n] : by_module(*params)) out << "  " << std::left << std::setw(20) << m << std::right << n << "\n";
  }
  out << std::fixed << std::setprecision(2) << "convolution GFLOPs per frame: mask " << flops[0] / 1e9 << ", pose "
      << flops[1] / 1e9 << "\n"
      << "activation MiB per frame (sum of layer outputs): mask " << double(act[0]) / (1 << 20) << ", pose "
      << double(act[1]) / (1 << 20) << "; peak newly held during the forward (activations, packed weights) " << double(peak) / (1 << 20) << "\n";
  return kOk;
}

int forward(const Args& a, std::ostream& out) {
  a.expect_positionals(0, 0);
  const auto wpath = a.value("--weights"), in = a.value("--input"), outp = a.value("--output");
  if (!wpath || !in || !outp) throw UsageError("model forward needs --weights W --input IN.h5 --output OUT.h5");
  check_output("--output", *outp, {*wpath, *in});
  weights::LoadedNetworks nets(weights::load_weights(*wpath), *wpath);
  const ModelConfig& cfg = nets.cfg;
  MaskNet& mask = nets.mask;
  PoseNet& pose = nets.pose;
  h5::silence_errors();
  std::vector<float> input;
  std::vector<hsize_t> dims;
  {
    if (!std::filesystem::is_regular_file(*in)) throw UsageError("--input " + *in + ": no such file");
    h5::H5Id f = [&] {
      try {
        return h5::open_file(*in);
      } catch (const std::exception& e) {
        throw UsageError("--input " + *in + ": " + e.what());
      }
    }();
    if (!h5::exists(f.get(), "input")) throw UsageError(*in + ": no dataset 'input' (S x C x H x W float32)");
    h5::H5Id ds = h5::check(H5Dopen2(f.get(), "input", H5P_DEFAULT), *in + ": open input");
    dims = h5::shape(ds.get());
    // Compared as stored (64-bit): a claim of 2^32 + 6 channels must not pass as 6.
    if (dims.size() != 4 || dims[1] != hsize_t(cfg.pose_channels()) || dims[2] != hsize_t(cfg.height()) ||
        dims[3] != hsize_t(cfg.width()) || dims[0] < 1 || dims[0] % hsize_t(cfg.window))
      throw UsageError(*in + ": input must be S x " + std::to_string(cfg.pose_channels()) + " x " + std::to_string(cfg.height()) +
                       " x " + std::to_string(cfg.width()) + " with S a multiple of the window " + std::to_string(cfg.window));
    // A parity tool's few windows, not a batch runner: a claim of millions of frames (an
    // unwritten dataset costs nothing on disk) must not size the buffer.
    constexpr hsize_t kMaxFrames = 1024;
    if (dims[0] > kMaxFrames)
      throw UsageError(*in + ": input claims " + std::to_string(dims[0]) + " frames; model forward takes at most " +
                       std::to_string(kMaxFrames));
    input.resize(dims[0] * dims[1] * dims[2] * dims[3]);
    h5::check(H5Dread(ds.get(), H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, input.data()), *in + ": read input");
  }
  const int S = int(dims[0]);
  // With pose.outside_input the input holds stage 2's channels, stage 1 reading the first half.
  layers::Floats xb(std::size_t(S) * ((cfg.pose_channels() + 15) / 16) * cfg.height() * cfg.width() * 16);
  const layers::Act x{xb.data(), S, cfg.pose_channels(), cfg.height(), cfg.width()};
  to_blocked(input, x);
  {
    layers::NoGrad no_grad;
    mask.forward({xb.data(), S, cfg.channels, cfg.height(), cfg.width()});
    pose.forward(x, cfg.window);
  }
  camera::TempFile tmp_file(*outp);
  const std::string& tmp = tmp_file.path();
  {
    h5::H5Id f = h5::create_file(tmp);
    auto put = [&](const std::string& name, const layers::Act& a) {
      const auto v = from_blocked(a);
      write_dataset(f.get(), name, {hsize_t(a.n), hsize_t(a.c), hsize_t(a.h), hsize_t(a.w)}, v.data());
    };
    put("masks", mask.masks());
    write_dataset(f.get(), "scores", {hsize_t(S), hsize_t(cfg.n_masks)}, mask.scores().data());
    static const char* planes[3] = {"xy", "zy", "xz"};
    for (int t = 0; t < cfg.stages; ++t)
      for (int p = 0; p < 3; ++p) put("heatmaps/stage" + std::to_string(t) + "/" + planes[p], pose.heatmap(t, p));
    write_dataset(f.get(), "joints_norm", {hsize_t(S), hsize_t(cfg.joints), 3}, pose.joints().data());
    h5::write_attr_string(f.get(), "config", cfg.json);
  }
  tmp_file.commit();
  out << "wrote " << *outp << ": " << S << " frames, " << cfg.stages << " stages\n";
  return kOk;
}

}  // namespace

int cmd_model(const std::vector<std::string>& argv, std::ostream& out, std::ostream& err) {
  if (argv.empty()) throw UsageError("model needs a subcommand: summary or forward (see 'yelan model --help')");
  const std::vector<std::string> rest(argv.begin() + 1, argv.end());
  try {
    if (argv[0] == "summary") return summary(Args("model summary", rest, {"--config"}, {"--json"}), out);
    if (argv[0] == "forward") return forward(Args("model forward", rest, {"--weights", "--input", "--output"}, {}), out);
  } catch (const ConfigError& e) {
    err << "yelan: error: " << printable(e.what()) << "\n";
    return kUsageError;
  } catch (const weights::WeightsError& e) {
    std::istringstream lines(e.what());
    for (std::string line; std::getline(lines, line);) err << "yelan: error: " << printable(line) << "\n";
    return kUsageError;
  } catch (const camera::h5::H5Failure& e) {
    err << "yelan: error: " << printable(e.what()) << "\n";
    return kUsageError;
  }
  throw UsageError("unknown model subcommand '" + argv[0] + "' (summary, forward)");
}

int weights_init(const std::vector<std::string>& argv, std::ostream& out) {
  const Args a("weights init", argv, {"--config", "--seed", "-o"}, {});
  a.expect_positionals(0, 0);
  const auto name = a.value("--config"), o = a.value("-o");
  if (!name || !o) throw UsageError("weights init needs --config NAME|FILE --seed N -o W.h5");
  check_output("-o", *o, {*name});
  const int seed = a.int_value_or("--seed", 0, 0, 2147483647);
  // A bad config's ConfigError reaches cli.cpp's handler: exit 2 with its message.
  const ModelConfig cfg = load_model_config(*name);
  MaskNet mask(cfg);
  PoseNet pose(cfg);
  mask.init(std::uint64_t(seed) * 2 + 1);
  pose.init(std::uint64_t(seed) * 2 + 2);
  layers::ParamList mp, pp;
  mask.params(mp);
  pose.params(pp);
  weights::randomise_batchnorm(mp, std::uint64_t(seed) * 2 + 3);
  weights::randomise_batchnorm(pp, std::uint64_t(seed) * 2 + 4);
  weights::save_weights(*o, weights::weights_of(cfg, mp, pp));
  out << "wrote " << *o << ": config " << cfg.name << ", seed " << seed << ", " << count(mp, true) << " + " << count(pp, true)
      << " parameters\n";
  return kOk;
}

}  // namespace yelan::cli
