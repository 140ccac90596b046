// weights::widen_mask_group, widen_pose_group and `yelan weights widen`: a wider stage 1 or
// stage 2 that starts where the narrow one was (same outputs in both BN modes) and can still
// learn its new channels; narrow_mask_group and `yelan weights narrow`, the way back for stage 1.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>

#include "engine/mask_net.h"
#include "engine/pose_net.h"
#include "layer_fd.h"
#include "weights_test_util.h"
#include "weights_tools/network_io.h"
#include "weights_tools/widen.h"

using namespace yelan;
using yelan::test::has;
using yelan::test::TempDir;
using yelan::test::yelan_cli;

namespace {

// tiny (mask width 0.125: 8 channels at the top) with another mask width.
ModelConfig tiny_mask(double width, int n_masks = 4) {
  return parse_model_config(R"({"name": "tiny-wide", "input": {"channels": 6, "sensor_height": 37, "sensor_width": 75,
    "downscale": 1, "window": 3}, "mask": {"width_mult": )" + std::to_string(width) + R"(, "n_masks": )" +
                                std::to_string(n_masks) + R"(}, "pose": {"width_mult": 0.125, "hidden": 12, "stages": 2,
    "joints": 13, "convlstm": "bidirectional"}})",
                            "test");
}

// A network with its parameter list, a parameter found by its state_dict key.
template <class N>
struct Built {
  N net;
  layers::ParamList params;
  explicit Built(const ModelConfig& c) : net(c) { net.params(params); }
  const layers::Param& param(const std::string& key) const {
    for (const auto& p : params)
      if (p.key == key) return *p.param;
    throw std::logic_error("no parameter " + key);
  }
};
using Net = Built<MaskNet>;
using Pose = Built<PoseNet>;

// The outputs' real lanes: masks, then scores.
std::vector<float> outputs(MaskNet& net, const layers::Act& x) {
  net.forward(x);
  std::vector<float> out;
  const layers::Act& m = net.masks();
  for (int n = 0; n < m.n; ++n)
    for (int c = 0; c < m.c; ++c)
      for (std::size_t p = 0; p < m.pixels(); ++p) out.push_back(m.data[((std::size_t(n) * m.cb() + c / 16) * m.pixels() + p) * 16 + c % 16]);
  out.insert(out.end(), net.scores().begin(), net.scores().end());
  return out;
}

}  // namespace

namespace {

// Outputs of the narrow net and of its widened copy on the same input, in both BN modes: the
// same up to rounding (the zero terms, batch statistics and softmax sums in another order).
template <class N, class Outputs>
void check_same_outputs(Built<N>& a, Built<N>& b, Outputs&& outputs_of, double min_scale, double tolerance) {
  for (const bool training : {false, true}) {
    INFO("training mode " << training);
    a.net.set_training(training);
    b.net.set_training(training);
    const std::vector<float> ya = outputs_of(a), yb = outputs_of(b);
    REQUIRE(ya.size() == yb.size());
    double worst = 0, scale = 0;
    for (std::size_t i = 0; i < ya.size(); ++i) {
      worst = std::max(worst, double(std::abs(ya[i] - yb[i])));
      scale = std::max(scale, double(std::abs(ya[i])));
    }
    CHECK(scale > min_scale);
    CHECK(worst <= tolerance * scale);
  }
}

void check_same_outputs(Net& a, Net& b, const layers::Act& x) {
  check_same_outputs(a, b, [&](Net& n) { return outputs(n.net, x); }, 0.1, 1e-5);
}

void load_widened(Net& b, const std::map<std::string, weights::Tensor>& group) {
  weights::Weights w;
  w.groups["mask"] = group;
  weights::load_group(w, "mask", b.params, "widened");
  b.net.weights_changed();
}

}  // namespace

TEST_CASE("widening 16 to 24 channels (whole 16-lane blocks, as the shipped net) keeps the outputs", "[weights][widen]") {
  const ModelConfig narrow = tiny_mask(0.25), wide = tiny_mask(0.375);
  REQUIRE(narrow.unet_width(0) == 16);
  Net a(narrow);
  a.net.init(2);
  weights::randomise_batchnorm(a.params, 3);
  Net b(wide);
  load_widened(b, weights::widen_mask_group(weights::group_of(a.params), narrow, wide, 4, "old.h5"));
  test::Owned x(2, narrow.channels, narrow.height(), narrow.width(), 5);
  check_same_outputs(a, b, x.act);
}

TEST_CASE("widening the mask net keeps its outputs and leaves the new channels free to learn", "[weights][widen]") {
  const ModelConfig narrow = load_model_config("tiny"), wide = tiny_mask(0.1875);  // 8 -> 12 channels at the top
  REQUIRE(wide.unet_width(0) == 12);
  Net a(narrow);
  a.net.init(5);
  weights::randomise_batchnorm(a.params, 6);
  const auto old_group = weights::group_of(a.params);
  const auto group = weights::widen_mask_group(old_group, narrow, wide, 7, "old.h5");

  Net b(wide);
  load_widened(b, group);
  test::Owned x(2, narrow.channels, narrow.height(), narrow.width(), 9);
  check_same_outputs(a, b, x.act);

  // A new channel's own weights are drawn; what reads it into an old channel is zero; the old
  // weights sit where the old net had them, the concatenated input's second half included.
  const auto& inc0 = b.param("inc.double_conv.0.weight");  // [12, 6, 3, 3]
  double new_rows = 0;
  for (std::size_t i = 8 * 54; i < 12 * 54; ++i) new_rows += std::abs(inc0.value[i]);
  CHECK(new_rows > 0);
  const auto& inc3 = b.param("inc.double_conv.3.weight");  // [12, 12, 3, 3]
  for (int o = 0; o < 8; ++o)
    for (int i = 8; i < 12; ++i) CHECK(inc3.value[std::size_t((o * 12 + i) * 9 + 4)] == 0.f);
  const auto& cat_old = old_group.at("up4.conv.double_conv.0.weight");   // [8, 16, 3, 3]: [skip 8 | up 8]
  const auto& cat_new = b.param("up4.conv.double_conv.0.weight");        // [12, 24, 3, 3]: [skip 12 | up 12]
  REQUIRE(cat_old.shape == weights::Shape{8, 16, 3, 3});
  CHECK(cat_new.value[std::size_t((3 * 24 + 12 + 5) * 9 + 2)] == cat_old.data[std::size_t((3 * 16 + 8 + 5) * 9 + 2)]);
  CHECK(cat_new.value[std::size_t((3 * 24 + 8) * 9 + 2)] == 0.f);  // the skip's new channel 8 into old channel 3

  // One backward in training mode: the zero weights from new channels get gradients.
  b.net.set_training(true);
  b.net.forward(x.act);
  test::Owned dm(b.net.masks(), 11);
  for (auto& p : b.params)
    for (std::size_t i = 0; i < p.param->grad.size(); ++i) p.param->grad[i] = 0.f;
  b.net.backward(x.act, dm.act, nullptr);
  double g = 0;
  for (int o = 0; o < 8; ++o)
    for (int i = 8; i < 12; ++i) g += std::abs(inc3.grad[std::size_t((o * 12 + i) * 9 + 4)]);
  CHECK(g > 0);
}

namespace {

// `widen` throws a WeightsError naming the old file and `what`.
template <class F>
void refuses(F&& widen, const std::string& what) {
  try {
    widen();
    FAIL("no error");
  } catch (const weights::WeightsError& e) {
    INFO(e.what());
    CHECK(has(e.what(), "old.h5"));
    CHECK(has(e.what(), what));
  }
}

}  // namespace

TEST_CASE("widening refuses a narrower net, other outputs and a group that is not the old config's", "[weights][widen]") {
  const ModelConfig narrow = load_model_config("tiny");
  Net a(narrow);
  a.net.init(1);
  const auto group = weights::group_of(a.params);
  const auto fails = [&](const ModelConfig& from, const ModelConfig& to, const std::string& what) {
    refuses([&] { weights::widen_mask_group(group, from, to, 1, "old.h5"); }, what);
  };
  fails(narrow, tiny_mask(0.0625), "narrower");
  fails(narrow, tiny_mask(0.25, 5), "'mask' section");  // n_masks
  fails(tiny_mask(0.25), tiny_mask(0.375), "shape");  // the group is 0.125's
  ModelConfig other_input = tiny_mask(0.25);
  other_input.json.replace(other_input.json.find("\"window\": 3"), 11, "\"window\": 4");
  fails(narrow, other_input, "'input' section");
}

namespace {

ModelConfig tiny_pose(double width, int hidden, const std::string& convlstm) {
  return parse_model_config(R"({"name": "tiny-pose-wide", "input": {"channels": 6, "sensor_height": 37, "sensor_width": 75,
    "downscale": 1, "window": 3}, "mask": {"width_mult": 0.125, "n_masks": 4}, "pose": {"width_mult": )" +
                                std::to_string(width) + R"(, "hidden": )" + std::to_string(hidden) +
                                R"(, "stages": 2, "joints": 13, "convlstm": ")" + convlstm + R"("}})",
                            "test");
}

// The joints and every stage's heatmaps (real lanes) of windows of 3 frames.
std::vector<float> pose_outputs(Pose& p, const layers::Act& x) {
  p.net.forward(x, 3);
  std::vector<float> out = p.net.joints();
  for (int t = 0; t < 2; ++t)
    for (int pl = 0; pl < 3; ++pl) {
      const layers::Act& m = p.net.heatmap(t, pl);
      for (int n = 0; n < m.n; ++n)
        for (int c = 0; c < m.c; ++c)
          for (std::size_t q = 0; q < m.pixels(); ++q) out.push_back(*m.lane(n, c, q));
    }
  return out;
}

}  // namespace

TEST_CASE("widening the pose net keeps its joints and heatmaps and leaves the new channels free to learn", "[weights][widen]") {
  for (const std::string mode : {"causal", "bidirectional"}) {
    INFO("convlstm " << mode);
    const ModelConfig narrow = tiny_pose(0.125, 12, mode), wide = tiny_pose(0.1875, 20, mode);
    REQUIRE(wide.resnet_mid() == 24);
    Pose a(narrow);
    a.net.init(3);
    weights::randomise_batchnorm(a.params, 4);
    const auto old_group = weights::group_of(a.params);
    Pose b(wide);
    {
      weights::Weights w;
      w.groups["pose"] = weights::widen_pose_group(old_group, narrow, wide, 5, "old.h5");
      weights::load_group(w, "pose", b.params, "widened");
      b.net.weights_changed();
    }
    test::Owned x(6, narrow.channels, narrow.height(), narrow.width(), 7);
    // 2e-4: in training mode BatchNorm over 6 images divides rounding by small batch spreads,
    // and the two widths' convolutions add their terms in different orders (the narrow net's
    // 8-channel layers split their sums into more partials: kernels/conv_direct.inl); a
    // misplaced weight moves the outputs by their own size.
    check_same_outputs(a, b, [&](Pose& p) { return pose_outputs(p, x.act); }, 0.01, 2e-4);
    // The gates' conv: [4 x 20 gates] x [24 features | 20 hidden]; old gate g, channel 3 sits
    // at row g * 20 + 3, the old hidden channel 5 at column 24 + 5; the new features 16..23 and
    // the new hidden 12..19 read into old gates are zero.
    const auto& og = old_group.at("cl.cell_list.0.conv.weight");  // [48, 28, k, k]
    const auto& ng = b.param("cl.cell_list.0.conv.weight");        // [80, 44, k, k]
    REQUIRE(og.shape[0] == 48);
    REQUIRE(og.shape[1] == 28);
    REQUIRE(ng.shape == weights::Shape{80, 44, og.shape[2], og.shape[3]});
    const std::int64_t kk = og.shape[2] * og.shape[3];
    for (int g = 0; g < 4; ++g) {
      CHECK(ng.value[std::size_t(((g * 20 + 3) * 44 + 24 + 5) * kk)] == og.data[std::size_t(((g * 12 + 3) * 28 + 16 + 5) * kk)]);
      CHECK(ng.value[std::size_t(((g * 20 + 3) * 44 + 2) * kk + 1)] == og.data[std::size_t(((g * 12 + 3) * 28 + 2) * kk + 1)]);
      CHECK(ng.value[std::size_t(((g * 20 + 3) * 44 + 17) * kk)] == 0.f);
      CHECK(ng.value[std::size_t(((g * 20 + 3) * 44 + 24 + 13) * kk)] == 0.f);
    }
    double new_rows = 0;
    for (std::int64_t i = 0; i < 44 * kk; ++i) new_rows += std::abs(ng.value[std::size_t((15 * 44) * kk + i)]);
    CHECK(new_rows > 0);  // gate 0's new channel 15 reads everything, with drawn weights

    // One backward in training mode: the zero weights from new channels get gradients.
    b.net.set_training(true);
    b.net.forward(x.act, 3);
    std::vector<float> dj(b.net.joints().size());
    for (std::size_t i = 0; i < dj.size(); ++i) dj[i] = float(std::sin(0.7 * double(i) + 1));
    for (auto& p : b.params)
      for (std::size_t i = 0; i < p.param->grad.size(); ++i) p.param->grad[i] = 0.f;
    b.net.backward(x.act, {}, dj.data());
    double g = 0;
    for (int gate = 0; gate < 4; ++gate) g += std::abs(ng.grad[std::size_t(((gate * 20 + 3) * 44 + 24 + 13) * kk)]);
    CHECK(g > 0);
  }
}

TEST_CASE("widening the pose net refuses a narrower net and changes beyond its widths", "[weights][widen]") {
  const ModelConfig narrow = tiny_pose(0.125, 12, "causal");
  Pose a(narrow);
  a.net.init(1);
  const auto group = weights::group_of(a.params);
  const auto fails = [&](const ModelConfig& from, const ModelConfig& to, const std::string& what) {
    refuses([&] { weights::widen_pose_group(group, from, to, 1, "old.h5"); }, what);
  };
  fails(narrow, tiny_pose(0.0625, 12, "causal"), "narrower");
  fails(narrow, tiny_pose(0.25, 8, "causal"), "narrower");
  fails(narrow, tiny_pose(0.25, 12, "bidirectional"), "'pose' section");
  fails(tiny_pose(0.25, 12, "causal"), tiny_pose(0.375, 12, "causal"), "shape");  // the group is 0.125's
}

TEST_CASE("yelan weights widen: a file that loads under the wider config and keeps the pose group", "[weights][widen][cli]") {
  TempDir dir("widen");
  REQUIRE(yelan_cli({"weights", "init", "--config", "tiny", "--seed", "3", "-o", dir / "w.h5"}).code == 0);
  {
    std::ofstream(dir / "wide.json") << R"({"name": "tiny-wide", "input": {"channels": 6, "sensor_height": 37, "sensor_width": 75,
      "downscale": 1, "window": 3}, "mask": {"width_mult": 0.25, "n_masks": 4}, "pose": {"width_mult": 0.125,
      "hidden": 12, "stages": 2, "joints": 13, "convlstm": "bidirectional"}})";
  }
  const auto r = yelan_cli({"weights", "widen", "--weights", dir / "w.h5", "--config", dir / "wide.json", "-o", dir / "x.h5"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(has(r.out, "widened from width_mult 0.125 to 0.25 (8 -> 16 channels"));
  const weights::Weights before = weights::load_weights(dir / "w.h5"), after = weights::load_weights(dir / "x.h5");
  CHECK(has(after.config_json, "tiny-wide"));
  CHECK(after.groups.at("mask").at("inc.double_conv.0.weight").shape == weights::Shape{16, 6, 3, 3});
  for (const auto& [k, t] : before.groups.at("pose")) CHECK(after.groups.at("pose").at(k).data == t.data);
  CHECK_NOTHROW(weights::LoadedNetworks(after, dir / "x.h5"));

  // The wider mask net joins a pose file of the old width under a config that describes it.
  const auto no_cfg = yelan_cli({"weights", "combine", "--mask", dir / "x.h5", "--pose", dir / "w.h5", "-o", dir / "c.h5"});
  CHECK(no_cfg.code == 2);
  CHECK(has(no_cfg.err, "give --config"));
  const auto comb = yelan_cli({"weights", "combine", "--mask", dir / "x.h5", "--pose", dir / "w.h5", "--config",
                               dir / "wide.json", "-o", dir / "c.h5"});
  INFO(comb.err);
  REQUIRE(comb.code == 0);
  CHECK(weights::load_weights(dir / "c.h5").groups.at("mask").at("up1.up.weight").data ==
        after.groups.at("mask").at("up1.up.weight").data);
  const auto narrow_cfg = yelan_cli({"weights", "combine", "--mask", dir / "x.h5", "--pose", dir / "w.h5", "--config",
                                     "tiny", "-o", dir / "d.h5"});
  CHECK(narrow_cfg.code == 2);
  CHECK(has(narrow_cfg.err, "'mask' section"));

  const auto missing = yelan_cli({"weights", "widen", "--weights", dir / "w.h5", "-o", dir / "y.h5"});
  CHECK(missing.code == 2);
  CHECK(has(missing.err, "--config"));
  const auto narrower = yelan_cli({"weights", "widen", "--weights", dir / "x.h5", "--config", "tiny", "-o", dir / "y.h5"});
  CHECK(narrower.code == 2);
  CHECK(has(narrower.err, "narrower"));
  CHECK(!std::filesystem::exists(dir / "y.h5"));
  const auto same = yelan_cli({"weights", "widen", "--weights", dir / "x.h5", "--config", dir / "wide.json", "-o", dir / "y.h5"});
  CHECK(same.code == 2);
  CHECK(has(same.err, "nothing to widen"));

  // The pose net alone: the mask group stays as it was.
  {
    std::ofstream(dir / "wide-pose.json") << R"({"name": "tiny-wide-pose", "input": {"channels": 6, "sensor_height": 37,
      "sensor_width": 75, "downscale": 1, "window": 3}, "mask": {"width_mult": 0.25, "n_masks": 4}, "pose": {"width_mult":
      0.25, "hidden": 16, "stages": 2, "joints": 13, "convlstm": "bidirectional"}})";
  }
  const auto p = yelan_cli({"weights", "widen", "--weights", dir / "x.h5", "--config", dir / "wide-pose.json", "-o", dir / "p.h5"});
  INFO(p.err);
  REQUIRE(p.code == 0);
  CHECK(has(p.out, "pose net widened from width_mult 0.125 to 0.25 (16 -> 32 channels into the ConvLSTM, hidden 12 -> 16"));
  CHECK(!has(p.out, "mask net widened"));
  const weights::Weights wp = weights::load_weights(dir / "p.h5");
  for (const auto& [k, t] : after.groups.at("mask")) CHECK(wp.groups.at("mask").at(k).data == t.data);
  CHECK(wp.groups.at("pose").at("in_cnn.0.weight").shape == weights::Shape{16, 6, 7, 7});
  CHECK_NOTHROW(weights::LoadedNetworks(wp, dir / "p.h5"));
}

TEST_CASE("widening to pose.outside_input: the events outside the mask read by zero weights, the same joints", "[weights][widen]") {
  const ModelConfig gated = tiny_pose(0.125, 12, "causal");
  std::string text = gated.json;
  text.insert(text.find("\"convlstm\""), "\"outside_input\": true, ");
  const ModelConfig outside = parse_model_config(text, "test");
  REQUIRE(outside.pose_channels() == 12);
  Pose a(gated);
  a.net.init(3);
  weights::randomise_batchnorm(a.params, 4);
  Pose b(outside);
  {
    weights::Weights w;
    w.groups["pose"] = weights::widen_pose_group(weights::group_of(a.params), gated, outside, 5, "old.h5");
    weights::load_group(w, "pose", b.params, "widened");
    b.net.weights_changed();
  }
  // The old net's input in the first six channels, anything in the other six.
  test::Owned x(6, gated.channels, gated.height(), gated.width(), 7), x2(6, outside.pose_channels(), gated.height(), gated.width(), 8);
  for (int n = 0; n < 6; ++n)
    for (std::size_t p = 0; p < x.act.pixels(); ++p)
      for (int c = 0; c < 6; ++c) *x2.act.lane(n, c, p) = *x.act.lane(n, c, p);
  for (const bool training : {false, true}) {
    INFO("training mode " << training);
    a.net.set_training(training);
    b.net.set_training(training);
    const std::vector<float> ya = pose_outputs(a, x.act), yb = pose_outputs(b, x2.act);
    REQUIRE(ya.size() == yb.size());
    double worst = 0;
    for (std::size_t i = 0; i < ya.size(); ++i) worst = std::max(worst, double(std::abs(ya[i] - yb[i])));
    CHECK(worst <= 1e-5);
  }
  const auto& w1 = b.param("in_cnn.0.weight");  // [c64, 12, 7, 7]
  REQUIRE(w1.shape[1] == 12);
  double outside_weights = 0;
  for (std::int64_t o = 0; o < w1.shape[0]; ++o)
    for (std::int64_t i = 6; i < 12; ++i)
      for (int k = 0; k < 49; ++k) outside_weights += std::abs(w1.value[std::size_t((o * 12 + i) * 49 + k)]);
  CHECK(outside_weights == 0);
  // And back is refused: widening only adds.
  refuses([&] { weights::widen_pose_group(weights::group_of(b.params), outside, gated, 1, "old.h5"); }, "drops pose.outside_input");
}

TEST_CASE("narrowing a widened stage 1 gives back the original, tensor for tensor", "[weights][narrow]") {
  const ModelConfig narrow = load_model_config("tiny"), wide = tiny_mask(0.1875);  // 8 <-> 12 channels at the top
  Net a(narrow);
  a.net.init(5);
  weights::randomise_batchnorm(a.params, 6);
  const auto old_group = weights::group_of(a.params);
  const auto back = weights::narrow_mask_group(weights::widen_mask_group(old_group, narrow, wide, 7, "old.h5"), wide, narrow, "wide.h5");
  REQUIRE(back.size() == old_group.size());
  for (const auto& [name, t] : old_group) {
    INFO(name);
    CHECK(back.at(name).shape == t.shape);
    CHECK(back.at(name).data == t.data);
  }
}

TEST_CASE("narrowing keeps each layer's first channels and each concatenated part's, and runs", "[weights][narrow]") {
  const ModelConfig wide = tiny_mask(0.1875), narrow = load_model_config("tiny");  // 12 -> 8 channels at the top
  Net a(wide);
  a.net.init(3);
  weights::randomise_batchnorm(a.params, 4);
  const auto group = weights::narrow_mask_group(weights::group_of(a.params), wide, narrow, "wide.h5");
  const auto& inc0 = a.param("inc.double_conv.0.weight");  // [12, 6, 3, 3] -> [8, 6, 3, 3]
  const auto& cut0 = group.at("inc.double_conv.0.weight");
  REQUIRE(cut0.shape == weights::Shape{8, 6, 3, 3});
  CHECK(std::equal(cut0.data.begin(), cut0.data.end(), inc0.value.data()));
  const auto& var = group.at("inc.double_conv.1.running_var");
  REQUIRE(var.shape == weights::Shape{8});
  for (int c = 0; c < 8; ++c) CHECK(var.data[std::size_t(c)] == a.param("inc.double_conv.1.running_var").value[std::size_t(c)]);
  // [skip 12 | up 12] -> [skip 8 | up 8]: output 3 reads skip channel 5 and up-sampled channel 5 as before.
  const auto& cat_wide = a.param("up4.conv.double_conv.0.weight");  // [12, 24, 3, 3]
  const auto& cat = group.at("up4.conv.double_conv.0.weight");
  REQUIRE(cat.shape == weights::Shape{8, 16, 3, 3});
  CHECK(cat.data[std::size_t((3 * 16 + 5) * 9 + 2)] == cat_wide.value[std::size_t((3 * 24 + 5) * 9 + 2)]);
  CHECK(cat.data[std::size_t((3 * 16 + 8 + 5) * 9 + 2)] == cat_wide.value[std::size_t((3 * 24 + 12 + 5) * 9 + 2)]);
  const auto& up = group.at("up1.up.weight");  // transposed: [in, out, 2, 2], both axes cut
  const auto& up_wide = a.param("up1.up.weight");
  REQUIRE(up_wide.shape.size() == 4);
  const std::int64_t wo = up_wide.shape[1], no = up.shape[1];
  CHECK(up.shape[0] < up_wide.shape[0]);
  CHECK(up.data[std::size_t(((2 * no + 1) * 2 + 1) * 2 + 0)] == up_wide.value[std::size_t(((2 * wo + 1) * 2 + 1) * 2 + 0)]);
  // The score head's last layer keeps its n_masks outputs and reads the kept features.
  CHECK(group.at("fc.weight").shape.at(0) == 4);

  // The cut net loads and computes masks and scores (not the wide net's).
  Net b(narrow);
  load_widened(b, group);
  test::Owned x(1, narrow.channels, narrow.height(), narrow.width(), 9);
  const std::vector<float> y = outputs(b.net, x.act);
  REQUIRE(!y.empty());
  CHECK(std::all_of(y.begin(), y.end(), [](float v) { return std::isfinite(v); }));
}

TEST_CASE("narrowing refuses a net no narrower, other changes and a group that is not the old config's", "[weights][narrow]") {
  const ModelConfig wide = tiny_mask(0.25);
  Net a(wide);
  a.net.init(1);
  const auto group = weights::group_of(a.params);
  const auto fails = [&](const ModelConfig& from, const ModelConfig& to, const std::string& what) {
    refuses([&] { weights::narrow_mask_group(group, from, to, "old.h5"); }, what);
  };
  fails(wide, tiny_mask(0.375), "narrower");
  fails(wide, tiny_mask(0.25), "narrower");
  fails(wide, tiny_mask(0.125, 5), "'mask' section");  // n_masks
  fails(tiny_mask(0.375), tiny_mask(0.125), "shape");   // the group is 0.25's
}

TEST_CASE("yelan weights narrow: a file that loads under the narrower config and keeps the pose group", "[weights][narrow][cli]") {
  TempDir dir("narrow");
  std::ofstream(dir / "wide.json") << tiny_mask(0.25).json;
  REQUIRE(yelan_cli({"weights", "init", "--config", dir / "wide.json", "--seed", "3", "-o", dir / "w.h5"}).code == 0);
  const auto r = yelan_cli({"weights", "narrow", "--weights", dir / "w.h5", "--config", "tiny", "-o", dir / "x.h5"});
  INFO(r.err);
  REQUIRE(r.code == 0);
  CHECK(has(r.out, "cut from width_mult 0.25 to 0.125 (16 -> 8 channels"));
  const weights::Weights before = weights::load_weights(dir / "w.h5"), after = weights::load_weights(dir / "x.h5");
  CHECK(after.groups.at("mask").at("inc.double_conv.0.weight").shape == weights::Shape{8, 6, 3, 3});
  for (const auto& [k, t] : before.groups.at("pose")) CHECK(after.groups.at("pose").at(k).data == t.data);
  CHECK_NOTHROW(weights::LoadedNetworks(after, dir / "x.h5"));

  const auto wider = yelan_cli({"weights", "narrow", "--weights", dir / "x.h5", "--config", dir / "wide.json", "-o", dir / "y.h5"});
  CHECK(wider.code == 2);
  CHECK(has(wider.err, "narrower"));
  CHECK(!std::filesystem::exists(dir / "y.h5"));
  const auto missing = yelan_cli({"weights", "narrow", "--weights", dir / "w.h5", "-o", dir / "y.h5"});
  CHECK(missing.code == 2);
  CHECK(has(missing.err, "--config"));
  std::ofstream(dir / "pose.json") << tiny_pose(0.125, 16, "bidirectional").json;  // a wider ConvLSTM
  const auto pose = yelan_cli({"weights", "narrow", "--weights", dir / "w.h5", "--config", dir / "pose.json", "-o", dir / "y.h5"});
  CHECK(pose.code == 2);
  CHECK(has(pose.err, "changes the pose net"));
  std::string stages = tiny_mask(0.125).json;  // narrower, and a pose net the old group does not fill
  stages.replace(stages.find("\"stages\": 2"), 11, "\"stages\": 3");
  std::ofstream(dir / "stages.json") << stages;
  const auto misfit = yelan_cli({"weights", "narrow", "--weights", dir / "w.h5", "--config", dir / "stages.json", "-o", dir / "y.h5"});
  CHECK(misfit.code == 2);
  CHECK(has(misfit.err, "w.h5's pose group does not fit --config"));
  CHECK(!std::filesystem::exists(dir / "y.h5"));
}
