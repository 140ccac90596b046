// weights::widen_mask_group and `yelan weights widen`: a wider stage 1 that starts where the
// narrow one was (same outputs in both BN modes) and can still learn its new channels.
#include <catch2/catch.hpp>

#include <cmath>

#include "engine/mask_net.h"
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

struct Net {
  MaskNet net;
  layers::ParamList params;
  explicit Net(const ModelConfig& c) : net(c) { net.params(params); }
  const layers::Param& param(const std::string& key) const {
    for (const auto& p : params)
      if (p.key == key) return *p.param;
    throw std::logic_error("no parameter " + key);
  }
};

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

// Outputs of the narrow net and of its widened copy on the same input, in both BN modes.
void check_same_outputs(Net& a, Net& b, const layers::Act& x) {
  for (const bool training : {false, true}) {
    INFO("training mode " << training);
    a.net.set_training(training);
    b.net.set_training(training);
    const std::vector<float> ya = outputs(a.net, x), yb = outputs(b.net, x);
    REQUIRE(ya.size() == yb.size());
    double worst = 0, scale = 0;
    for (std::size_t i = 0; i < ya.size(); ++i) {
      worst = std::max(worst, double(std::abs(ya[i] - yb[i])));
      scale = std::max(scale, double(std::abs(ya[i])));
    }
    CHECK(scale > 0.1);
    CHECK(worst <= 1e-5 * scale);  // the same up to rounding (the zero terms change the sums' order)
  }
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

TEST_CASE("widening refuses a narrower net, other outputs and a group that is not the old config's", "[weights][widen]") {
  const ModelConfig narrow = load_model_config("tiny");
  Net a(narrow);
  a.net.init(1);
  const auto group = weights::group_of(a.params);
  const auto fails = [&](const ModelConfig& from, const ModelConfig& to, const std::string& what) {
    try {
      weights::widen_mask_group(group, from, to, 1, "old.h5");
      FAIL("no error");
    } catch (const weights::WeightsError& e) {
      INFO(e.what());
      CHECK(has(e.what(), "old.h5"));
      CHECK(has(e.what(), what));
    }
  };
  fails(narrow, tiny_mask(0.0625), "narrower");
  fails(narrow, tiny_mask(0.25, 5), "'mask' section");  // n_masks
  fails(tiny_mask(0.25), tiny_mask(0.375), "shape");  // the group is 0.125's
  ModelConfig other_input = tiny_mask(0.25);
  other_input.json.replace(other_input.json.find("\"window\": 3"), 11, "\"window\": 4");
  fails(narrow, other_input, "'input' section");
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
}
