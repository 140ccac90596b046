// Forward parity with the PyTorch reference (weights_tools/reference): random weights and
// a random window from weights_tools/make_parity_case.py, loaded into our networks, every
// head compared. Skipped, loudly, where Debian's python3-torch is not installed.
#include <catch2/catch.hpp>
#include <hdf5.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <map>
#include <optional>

#include "engine/mask_net.h"
#include "engine/model_config.h"
#include "engine/pose_net.h"
#include "layer_fd.h"
#include "weights_tools/network_io.h"
#include "weights_tools/weights_file.h"

using namespace yelan;

namespace {

std::string source_dir() { return YELAN_SOURCE_DIR; }

void require_torch() {
  if (std::system("/usr/bin/python3 -c 'import torch, h5py' >/dev/null 2>&1") != 0) {
    std::printf("SKIP: PyTorch parity NOT checked: /usr/bin/python3 cannot import torch and h5py "
                "(apt-get install python3-torch python3-h5py, or scripts/setup-debian --reference)\n");
    std::fflush(stdout);
    std::exit(77);
  }
}

struct Array {
  std::vector<hsize_t> dims;
  std::vector<float> data;
};

Array read_dataset(const std::string& file, const std::string& name) {
  Array a;
  const hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  REQUIRE(f >= 0);
  const hid_t d = H5Dopen2(f, name.c_str(), H5P_DEFAULT);
  INFO(file << ": " << name);
  REQUIRE(d >= 0);
  const hid_t sp = H5Dget_space(d);
  a.dims.resize(H5Sget_simple_extent_ndims(sp));
  H5Sget_simple_extent_dims(sp, a.dims.data(), nullptr);
  std::size_t n = 1;
  for (auto v : a.dims) n *= v;
  a.data.resize(n);
  REQUIRE(H5Dread(d, H5T_NATIVE_FLOAT, H5S_ALL, H5S_ALL, H5P_DEFAULT, a.data.data()) >= 0);
  H5Sclose(sp);
  H5Dclose(d);
  H5Fclose(f);
  return a;
}

using weights::load_group;  // every name and shape checked both ways

// NCHW (n, c, h, w) array -> blocked activation.
yelan::test::Owned to_act(const Array& a) {
  const int n = int(a.dims[0]), c = int(a.dims[1]), h = int(a.dims[2]), w = int(a.dims[3]);
  yelan::test::Owned o(n, c, h, w);
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < c; ++k)
      for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
          o.mem[(((std::size_t(i) * o.act.cb() + k / 16) * h + y) * w + x) * 16 + k % 16] =
              a.data[((std::size_t(i) * c + k) * h + y) * w + x];
  return o;
}

// Both networks of a config, holding a weights file's tensors.
struct Nets {
  MaskNet mask;
  PoseNet pose;
  layers::ParamList mp, pp;
  Nets(const ModelConfig& cfg, const weights::Weights& w, bool training) : mask(cfg), pose(cfg) {
    mask.params(mp);
    pose.params(pp);
    load_group(w, "mask", mp);
    load_group(w, "pose", pp);
    weights_changed();
    mask.set_training(training);
    pose.set_training(training);
  }
  void weights_changed() {
    mask.weights_changed();
    pose.weights_changed();
  }
};

// max |ours - ref| / max |ref| over a blocked activation against an NCHW reference.
double rel_error(const layers::Act& ours, const Array& ref) {
  REQUIRE(ref.dims.size() == 4);
  REQUIRE(int(ref.dims[0]) == ours.n);
  REQUIRE(int(ref.dims[1]) == ours.c);
  REQUIRE(int(ref.dims[2]) == ours.h);
  REQUIRE(int(ref.dims[3]) == ours.w);
  double worst = 0, scale = 0;
  for (int i = 0; i < ours.n; ++i)
    for (int k = 0; k < ours.c; ++k)
      for (int y = 0; y < ours.h; ++y)
        for (int x = 0; x < ours.w; ++x) {
          const double r = ref.data[((std::size_t(i) * ours.c + k) * ours.h + y) * ours.w + x];
          const double o = ours.data[(((std::size_t(i) * ours.cb() + k / 16) * ours.h + y) * ours.w + x) * 16 + k % 16];
          worst = std::max(worst, std::abs(o - r));
          scale = std::max(scale, std::abs(r));
        }
  return worst / scale;
}

double rel_error(const std::vector<float>& ours, const Array& ref) {
  REQUIRE(ours.size() == ref.data.size());
  double worst = 0, scale = 0;
  for (std::size_t i = 0; i < ours.size(); ++i) {
    worst = std::max(worst, std::abs(double(ours[i]) - ref.data[i]));
    scale = std::max(scale, std::abs(double(ref.data[i])));
  }
  return worst / scale;
}

}  // namespace

TEST_CASE("forward parity with PyTorch on the tiny, small and paper configs, tiny at head_stride 4, with hourglass_skip, depth_map and outside_input", "[parity]") {
  require_torch();
  const auto dir = std::filesystem::temp_directory_path() / ("yelan-parity-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  double worst_overall = 0, worst_winograd = 0;
  // paper at window 1: the exact networks of the paper configuration (the window only sets
  // how often the ConvLSTM cell repeats), at a cost PyTorch can afford in a test.
  {
    std::ifstream in(source_dir() + "/weights_tools/configs/paper.json");
    auto j = nlohmann::json::parse(in);
    j["name"] = "paper-w1";
    j["input"]["window"] = 1;
    std::ofstream(dir / "paper-w1.json") << j.dump(2);
  }
  // tiny with pose.head_stride 4: layer2 at layer1's resolution, heatmaps twice as fine
  {
    std::ifstream in(source_dir() + "/weights_tools/configs/tiny.json");
    auto j = nlohmann::json::parse(in);
    j["name"] = "tiny-s4";
    j["pose"]["head_stride"] = 4;
    std::ofstream(dir / "tiny-s4.json") << j.dump(2);
  }
  // tiny with pose.hourglass_skip: each hourglass's mid resolution added past its bottleneck
  {
    std::ifstream in(source_dir() + "/weights_tools/configs/tiny.json");
    auto j = nlohmann::json::parse(in);
    j["name"] = "tiny-skip";
    j["pose"]["hourglass_skip"] = true;
    std::ofstream(dir / "tiny-skip.json") << j.dump(2);
  }
  // tiny with pose.depth_map: z from a fourth hourglass's depth maps under the xy maps
  {
    std::ifstream in(source_dir() + "/weights_tools/configs/tiny.json");
    auto j = nlohmann::json::parse(in);
    j["name"] = "tiny-depth";
    j["pose"]["depth_map"] = true;
    std::ofstream(dir / "tiny-depth.json") << j.dump(2);
  }
  // tiny with pose.outside_input: stage 2 reads [inside the mask | outside it], 12 channels
  {
    std::ifstream in(source_dir() + "/weights_tools/configs/tiny.json");
    auto j = nlohmann::json::parse(in);
    j["name"] = "tiny-outside";
    j["pose"]["outside_input"] = true;
    std::ofstream(dir / "tiny-outside.json") << j.dump(2);
  }
  // the default's shapes with stage 1 on the input pooled 2 x 2 (130 x 173 -> 65 x 86 -> 130 x 173)
  {
    std::ifstream in(source_dir() + "/weights_tools/configs/small.json");
    auto j = nlohmann::json::parse(in);
    j["name"] = "small-p2";
    j["mask"]["pool"] = 2;
    std::ofstream(dir / "small-p2.json") << j.dump(2);
  }
  for (const std::string& name : std::vector<std::string>{"tiny", "small", (dir / "paper-w1.json").string(),
                                                          (dir / "tiny-s4.json").string(), (dir / "small-p2.json").string(),
                                                          (dir / "tiny-skip.json").string(), (dir / "tiny-depth.json").string(),
                                                          (dir / "tiny-outside.json").string()}) {
    const std::string stem = std::filesystem::path(name).stem().string();
    const std::string cs = (dir / (stem + ".h5")).string();
    const std::string cmd = "cd '" + source_dir() + "' && /usr/bin/python3 weights_tools/make_parity_case.py --config '" +
                            name + "' --seed 7 -o '" + cs + "' > /dev/null";
    INFO(cmd);
    REQUIRE(std::system(cmd.c_str()) == 0);
    const ModelConfig cfg = load_model_config(name);
    Nets nets(cfg, weights::load_weights((dir / (stem + ".weights.h5")).string()), false);
    MaskNet& mask = nets.mask;
    PoseNet& pose = nets.pose;
    auto x = to_act(read_dataset(cs, "input"));
    // As trained (eval BN its own pass), and as deployed (NoGrad: BN folded into the convs)
    // with the direct convolution; then as deployed with Winograd, whose different rounding
    // the heatmaps' softmax amplifies: reported, and held to a looser bound.
    for (int mode : {0, 1, 2}) {
    const bool folded = mode > 0;
    std::optional<yelan::layers::NoGrad> no_grad;
    if (folded) no_grad.emplace();
    // Modes 0 and 1 with the direct convolution: an eval-mode ConvBn asks for Winograd too
    // (blocks.cpp), so mode 0 must forbid it to be held to the direct bound.
    yelan::layers::winograd_allowed() = mode == 2;
    mask.forward({x.act.data, x.act.n, cfg.channels, x.act.h, x.act.w});  // the first channels (one block)
    pose.forward(x.act, cfg.window);
    std::map<std::string, double> err;
    err["masks"] = rel_error(mask.masks(), read_dataset(cs, "masks"));
    err["scores"] = rel_error(mask.scores(), read_dataset(cs, "scores"));
    err["joints_norm"] = rel_error(pose.joints(), read_dataset(cs, "joints_norm"));
    static const char* planes[3] = {"xy", "zy", "xz"};
    for (int t = 0; t < cfg.stages; ++t)
      for (int p = 0; p < 3; ++p) {
        const std::string key = "heatmaps/stage" + std::to_string(t) + "/" + planes[p];
        err[key] = rel_error(pose.heatmap(t, p), read_dataset(cs, key));
      }
    for (auto& [k, e] : err) {
      static const char* mode_name[3] = {"", "folded", "folded+winograd"};
      std::printf("parity %-8s %-15s %-22s max|ours - torch| / max|torch| = %.3g\n", stem.c_str(),
                  mode_name[mode], k.c_str(), e);
      INFO(stem << " " << mode_name[mode] << " " << k << ": max |ours - torch| / max |torch| = " << e);
      CHECK(e < (mode == 2 ? 3e-4 : 1e-4));
      if (mode < 2) worst_overall = std::max(worst_overall, e);
      else worst_winograd = std::max(worst_winograd, e);
    }
    }
  }
  yelan::layers::winograd_allowed() = true;
  WARN("forward parity, worst relative error over every head: " << worst_overall
       << " (inference with BN folded and Winograd: " << worst_winograd << ")");
  std::filesystem::remove_all(dir);
}

#include "engine/losses.h"

namespace {

double attr(const std::string& file, const std::string& name) {
  const hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  REQUIRE(f >= 0);
  const hid_t a = H5Aopen(f, name.c_str(), H5P_DEFAULT);
  REQUIRE(a >= 0);
  double v = 0;
  REQUIRE(H5Aread(a, H5T_NATIVE_DOUBLE, &v) >= 0);
  H5Aclose(a);
  H5Fclose(f);
  return v;
}

// max |ours - ref| / max |ref| for one parameter's gradient (or buffer).
double rel_error(const float* ours, const Array& ref) {
  double worst = 0, scale = 0;
  for (std::size_t i = 0; i < ref.data.size(); ++i) {
    worst = std::max(worst, std::abs(double(ours[i]) - ref.data[i]));
    scale = std::max(scale, std::abs(double(ref.data[i])));
  }
  return scale > 0 ? worst / scale : worst;
}

}  // namespace

// Gradient parity. A float32 gradient of a deep ReLU net with small BN batches is itself
// ill-conditioned: an activation within rounding of a ReLU kink flips, and BN's batch
// statistics spread the flip over its channel. So the yardstick is PyTorch in float64
// (exact for our purpose): ours must be as close to it as PyTorch's own float32 result
// (within 3x, or 1e-4), and within 1e-4 wherever float32 itself is well conditioned.
TEST_CASE("training-mode losses and every gradient match PyTorch (tiny config)", "[parity]") {
  require_torch();
  const bool eval_mode = std::getenv("YELAN_PARITY_EVAL") != nullptr;  // isolates BN's batch statistics
  const auto dir = std::filesystem::temp_directory_path() / ("yelan-grad-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  double worst_conditioned = 0, worst_any = 0;
  std::string worst_key;
  int conditioned = 0, total = 0;
  for (int seed : {5, 7}) {
    const std::string cs = (dir / "tiny.h5").string(), ws = (dir / "tiny.weights.h5").string(),
                      g32 = (dir / "g32.h5").string(), g64 = (dir / "g64.h5").string();
    const std::string grad = "/usr/bin/python3 weights_tools/make_grad_case.py --weights '" + ws + "' --seed " +
                             std::to_string(seed) + (eval_mode ? " --eval" : "");
    const std::string cmd = "cd '" + source_dir() + "' && /usr/bin/python3 weights_tools/make_parity_case.py --config tiny --seed 11 -o '" +
                            cs + "' > /dev/null && " + grad + " -o '" + g32 + "' > /dev/null && " + grad + " --double -o '" +
                            g64 + "' > /dev/null";
    INFO(cmd);
    REQUIRE(std::system(cmd.c_str()) == 0);
    const ModelConfig cfg = load_model_config("tiny");
    Nets nets(cfg, weights::load_weights(ws), !eval_mode);
    MaskNet& mask = nets.mask;
    PoseNet& pose = nets.pose;
    auto x = to_act(read_dataset(g32, "input"));
    auto labels = to_act(read_dataset(g32, "labels"));
    const Array target = read_dataset(g32, "target"), valid = read_dataset(g32, "valid");

    mask.forward(x.act);
    yelan::test::Owned dmasks(mask.masks());
    std::vector<float> dscores;
    const MaskLoss ml = mask_loss(mask, labels.act, dmasks.act, dscores);
    mask.backward(x.act, dmasks.act, dscores.data());
    pose.forward(x.act, cfg.window);
    std::vector<PoseNet::StageGrads> dheat;
    std::vector<layers::Floats> store;
    const HpeLoss hl = hpe_loss(pose, cfg.stages, target.data.data(), valid.data.data(), dheat, store);
    pose.backward(x.act, dheat, nullptr);

    const double lm = attr(g64, "loss_mask"), lp = attr(g64, "loss_pose");
    std::printf("grad parity seed %d: loss_mask ours %.8g torch64 %.8g; loss_pose ours %.8g torch64 %.8g\n", seed,
                ml.total, lm, hl.total, lp);
    CHECK(std::abs(ml.total - lm) <= 1e-5 * std::abs(lm));
    CHECK(std::abs(hl.total - lp) <= 1e-5 * std::abs(lp));
    for (auto [group, params] : {std::pair{"mask", &nets.mp}, std::pair{"pose", &nets.pp}}) {
      for (auto& p : *params) {
        const std::string key = std::string(group) + "/" + p.key;
        if (!p.param->trainable) {
          const Array ref = read_dataset(g32, std::string("after_") + group + "/" + p.key);
          INFO(key << " after the training forward");
          CHECK(rel_error(p.param->value.data(), ref) < 1e-5);
          continue;
        }
        const Array exact = read_dataset(g64, std::string("grad_") + group + "/" + p.key);
        const Array t32 = read_dataset(g32, std::string("grad_") + group + "/" + p.key);
        double scale = 0;
        for (float v : exact.data) scale = std::max(scale, double(std::abs(v)));
        if (scale < 1e-9) {  // biases right before a softmax: exactly zero (shift invariance)
          for (std::size_t i = 0; i < p.param->numel(); ++i) REQUIRE(std::abs(p.param->grad[i]) < 1e-7);
          continue;
        }
        std::vector<float> t32v(t32.data.begin(), t32.data.end());
        const double e_ours = rel_error(p.param->grad.data(), exact), e_t32 = rel_error(t32v.data(), exact);
        ++total;
        INFO(key << ": ours vs float64 " << e_ours << ", PyTorch float32 vs float64 " << e_t32);
        CHECK(e_ours <= std::max(1e-4, 3 * e_t32));
        if (e_t32 < 1e-5) {  // float32 is well conditioned here: demand parity
          ++conditioned;
          CHECK(e_ours < 1e-4);
          worst_conditioned = std::max(worst_conditioned, e_ours);
        }
        if (e_ours > worst_any) {
          worst_any = e_ours;
          worst_key = key + " (seed " + std::to_string(seed) + ", PyTorch float32: " + std::to_string(e_t32) + ")";
        }
      }
    }
  }
  std::printf("grad parity: %d of %d gradients well conditioned in float32; worst of ours vs float64 there %.3g; "
              "worst overall %.3g at %s\n", conditioned, total, worst_conditioned, worst_any, worst_key.c_str());
  CHECK(conditioned >= 150);  // the strict 1e-4 check must cover many tensors (277 of 1348 here)
  std::filesystem::remove_all(dir);
}

#include "engine/adam.h"

// 20 Adam steps. Adam normalises each gradient element, so elements whose float32 gradient
// is rounding noise (see the gradient test above) take full-size steps of arbitrary sign:
// float32 training drifts from exact training by itself. PyTorch float32 drifts from
// PyTorch float64 by up to 6e-3 in the pose loss over these 20 steps (and by 6e-5 in the
// mask loss). So: the mask net within 1e-3 of PyTorch at every step; the pose net within
// 1e-5 for the first 3 steps and, over all 20, no farther from float64 than 3x PyTorch's
// own float32 drift.
TEST_CASE("20 training steps from the same weights and batches give PyTorch's losses", "[parity]") {
  require_torch();
  const auto dir = std::filesystem::temp_directory_path() / ("yelan-train-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string cs = (dir / "tiny.h5").string(), ws = (dir / "tiny.weights.h5").string(),
                    t32 = (dir / "train32.h5").string(), t64 = (dir / "train64.h5").string();
  const std::string train = "/usr/bin/python3 weights_tools/make_train_case.py --weights '" + ws + "' --steps 20 --seed 9";
  const std::string cmd = "cd '" + source_dir() + "' && /usr/bin/python3 weights_tools/make_parity_case.py --config tiny --seed 13 -o '" +
                          cs + "' > /dev/null && " + train + " -o '" + t32 + "' > /dev/null && " + train + " --double -o '" +
                          t64 + "' > /dev/null";
  INFO(cmd);
  REQUIRE(std::system(cmd.c_str()) == 0);
  const ModelConfig cfg = load_model_config("tiny");
  Nets nets(cfg, weights::load_weights(ws), true);
  MaskNet& mask = nets.mask;
  PoseNet& pose = nets.pose;
  AdamOptions opt;
  opt.lr = 1e-3;
  opt.weight_decay = 1e-5;
  Adam adam_mask(nets.mp, opt), adam_pose(nets.pp, opt);
  const Array m32 = read_dataset(t32, "loss_mask"), p32 = read_dataset(t32, "loss_pose");
  const Array m64 = read_dataset(t64, "loss_mask"), p64 = read_dataset(t64, "loss_pose");
  REQUIRE(m32.data.size() == 20);
  double pose_ours = 0, pose_torch = 0, mask_worst = 0;
  for (int step = 0; step < 20; ++step) {
    const std::string g = "step" + std::to_string(step) + "/";
    auto x = to_act(read_dataset(t32, g + "input"));
    auto labels = to_act(read_dataset(t32, g + "labels"));
    const Array target = read_dataset(t32, g + "target"), valid = read_dataset(t32, g + "valid");

    adam_mask.zero_grad();
    mask.forward(x.act);
    yelan::test::Owned dmasks(mask.masks());
    std::vector<float> dscores;
    const double lm = mask_loss(mask, labels.act, dmasks.act, dscores).total;
    mask.backward(x.act, dmasks.act, dscores.data());
    adam_mask.step();
    mask.weights_changed();

    adam_pose.zero_grad();
    pose.forward(x.act, cfg.window);
    std::vector<PoseNet::StageGrads> dheat;
    std::vector<layers::Floats> store;
    const double lp = hpe_loss(pose, cfg.stages, target.data.data(), valid.data.data(), dheat, store).total;
    pose.backward(x.act, dheat, nullptr);
    adam_pose.step();
    pose.weights_changed();

    auto rel = [](double a, double b) { return std::abs(a - b) / std::abs(b); };
    const double em = std::max(rel(lm, m32.data[step]), rel(lm, m64.data[step]));
    const double ep = rel(lp, p64.data[step]), ep_torch = rel(p32.data[step], p64.data[step]);
    std::printf("train parity step %2d: mask ours %.7f torch %.7f; pose ours %.7f torch32 %.7f torch64 %.7f "
                "(ours vs 64: %.2g, torch32 vs 64: %.2g)\n",
                step, lm, m32.data[step], lp, p32.data[step], p64.data[step], ep, ep_torch);
    INFO("step " << step);
    CHECK(em <= 1e-3);
    // Before Adam has stepped twice the losses agree to float32's rounding. From then on its
    // normalisation (m / sqrt(v)) turns gradients that are rounding noise into whole steps, and
    // the drift depends on the CPU's summation order: on an AVX2-only AMD EPYC (Zen 3) step 2
    // drifted 2.5e-5 (AVX2) and 1.4e-5 (the scalar kernels) from float64, PyTorch float32 2.8e-5
    // one step later; 1e-5 had held there on the AVX-512 CPUs. After step 2: the bound below.
    if (step < 2) CHECK(ep <= 1e-5);
    if (step == 2) CHECK(ep <= 1e-4);
    mask_worst = std::max(mask_worst, em);
    pose_ours = std::max(pose_ours, ep);
    pose_torch = std::max(pose_torch, ep_torch);
  }
  std::printf("train parity: mask loss worst %.3g; pose loss vs float64 worst %.3g (PyTorch float32: %.3g)\n", mask_worst,
              pose_ours, pose_torch);
  CHECK(pose_ours <= std::max(1e-3, 3 * pose_torch));
  std::filesystem::remove_all(dir);
}
