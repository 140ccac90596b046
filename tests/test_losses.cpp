// The mask loss's sample weights: a weighted mean of what each sample alone would give, and
// the windows with nobody in their current frame found from the labels; its Dice term's
// value on masks whose overlap is known, and its gradient against finite differences.
#include <catch2/catch.hpp>

#include <algorithm>
#include <cmath>
#include <random>

#include "engine/losses.h"
#include "engine/model_config.h"
#include "layer_fd.h"
#include "weights_tools/network_io.h"

using namespace yelan;

namespace {

struct Scored {
  MaskLoss loss;
  std::vector<float> dmasks, dscores;
};

// The tiny mask net in eval mode (fixed BN statistics: each sample's output is its own),
// on samples `first`.. of x, against labels of the same samples.
Scored score(MaskNet& net, const test::Owned& x, const test::Owned& labels, int first, int n,
             const std::vector<float>& weights) {
  const std::size_t per_x = x.act.floats() / std::size_t(x.act.n), per_l = labels.act.floats() / std::size_t(labels.act.n);
  const layers::Act xs{x.act.data + per_x * std::size_t(first), n, x.act.c, x.act.h, x.act.w};
  const layers::Act ls{labels.act.data + per_l * std::size_t(first), n, labels.act.c, labels.act.h, labels.act.w};
  net.forward(xs);
  test::Owned dm(net.masks());
  Scored s;
  s.loss = mask_loss(net, ls, dm.act, s.dscores, weights);
  s.dmasks.assign(dm.act.data, dm.act.data + dm.act.floats());
  return s;
}

// Every stride-th real logit of m moved by +-0.01: the central difference of loss_of() (a
// loss of m's current values) against the analytic gradient g.
template <class LossOf>
void check_gradient_by_differences(const layers::Act& m, const std::vector<float>& g, std::size_t stride, LossOf loss_of) {
  double worst = 0, scale = 0;
  for (std::size_t k = 0; k < g.size(); k += stride) {
    if (int(k % 16) >= m.c) continue;
    const float x0 = m.data[k];
    m.data[k] = x0 + 0.01f;
    const float xp = m.data[k];
    const double lp = loss_of();
    m.data[k] = x0 - 0.01f;
    const float xm = m.data[k];
    const double lm = loss_of();
    m.data[k] = x0;
    worst = std::max(worst, std::abs((lp - lm) / double(xp - xm) - double(g[k])));
    scale = std::max(scale, std::abs(double(g[k])));
  }
  REQUIRE(scale > 0);
  CHECK(worst < 1e-4 * scale);
}

// The tiny config with pose.depth_map.
ModelConfig tiny_depth() {
  std::string text = load_model_config("tiny").json;
  text.insert(text.find("\"convlstm\""), "\"depth_map\": true, ");
  return parse_model_config(text, "tiny-depth");
}

}  // namespace

TEST_CASE("mask loss: sample weights give the weighted mean of each sample's own loss", "[train][losses]") {
  const ModelConfig cfg = load_model_config("tiny");
  MaskNet net(cfg);
  net.init(11);
  net.set_training(false);
  test::Owned x(3, cfg.channels, cfg.height(), cfg.width(), 21);
  net.forward(x.act);
  test::Owned labels(net.masks());
  // Sample 0: nobody now, someone in a later frame; 1 and 2: a blob now.
  labels.for_each_real([&](std::size_t k) {
    const std::size_t per = labels.act.floats() / 3, i = k / per, c = k % 16, p = (k % per) / 16;
    const bool blob = (p % 97) < 30;
    labels.mem[k] = (i == 0 ? c == 3 : true) && blob ? 1.f : 0.f;
  });

  SECTION("weights of 1 are no weights, to the bit") {
    const Scored a = score(net, x, labels, 0, 3, {}), b = score(net, x, labels, 0, 3, {1.f, 1.f, 1.f});
    CHECK(a.loss.total == b.loss.total);
    CHECK(a.dmasks == b.dmasks);
    CHECK(a.dscores == b.dscores);
  }
  SECTION("weighted mean over samples, gradients scaled alike") {
    const std::vector<float> w{3.f, 1.f, 0.5f};
    const Scored all = score(net, x, labels, 0, 3, w);
    double want = 0;
    std::vector<Scored> alone;
    for (int i = 0; i < 3; ++i) {
      alone.push_back(score(net, x, labels, i, 1, {}));
      want += w[std::size_t(i)] * alone.back().loss.total / 4.5;
    }
    CHECK(all.loss.total == Approx(want).epsilon(1e-6));
    const std::size_t per = all.dmasks.size() / 3, per_s = all.dscores.size() / 3;
    double worst = 0;
    for (int i = 0; i < 3; ++i) {
      const double f = w[std::size_t(i)] / 4.5;  // alone, a sample's weight share is 1
      for (std::size_t k = 0; k < per; ++k)
        worst = std::max(worst, std::abs(all.dmasks[std::size_t(i) * per + k] - f * alone[std::size_t(i)].dmasks[k]));
      for (std::size_t k = 0; k < per_s; ++k)
        CHECK(all.dscores[std::size_t(i) * per_s + k] == Approx(f * alone[std::size_t(i)].dscores[k]).epsilon(1e-5));
    }
    CHECK(worst < 1e-9);  // the gradients are ~1e-5: this is ~1e-4 relative
  }
  SECTION("a zero weight takes a sample out; wrong counts and a zero sum are refused") {
    const Scored two = score(net, x, labels, 0, 3, {1.f, 1.f, 0.f}), first = score(net, x, labels, 0, 2, {});
    CHECK(two.loss.total == Approx(first.loss.total).epsilon(1e-12));
    std::vector<float> ds;
    net.forward(x.act);
    test::Owned dm(net.masks());
    CHECK_THROWS_AS(mask_loss(net, labels.act, dm.act, ds, {1.f, 1.f}), std::invalid_argument);
    CHECK_THROWS_AS(mask_loss(net, labels.act, dm.act, ds, {0.f, 0.f, 0.f}), std::invalid_argument);
  }
  SECTION("nobody_weights: a window is empty by its current frame, not its future ones") {
    const std::vector<float> w = nobody_weights(labels.act, 4.f);
    REQUIRE(w.size() == 3);
    CHECK(w[0] == 4.f);
    CHECK(w[1] == 1.f);
    CHECK(w[2] == 1.f);
  }
}

TEST_CASE("mask loss: the Dice term scores the current mask's overlap, its gradient by finite differences",
          "[train][losses]") {
  const ModelConfig cfg = load_model_config("tiny");
  MaskNet net(cfg);
  net.init(5);
  net.set_training(false);
  test::Owned x(3, cfg.channels, cfg.height(), cfg.width(), 8);
  net.forward(x.act);
  const layers::Act& m = net.masks();
  const std::size_t per = m.floats() / 3, P = m.pixels();
  test::Owned labels(m);
  // Sample 0: nobody in any frame; 1: a blob now; 2: a blob in a later frame only.
  labels.for_each_real([&](std::size_t k) {
    const std::size_t i = k / per, c = k % 16, p = (k % per) / 16;
    const bool blob = (p % 31) < 9;
    labels.mem[k] = blob && ((i == 1 && c == 0) || (i == 2 && c == 2)) ? 1.f : 0.f;
  });
  test::Owned dm(m);
  std::vector<float> ds;
  auto set_logits = [&](auto&& f) {
    for (std::size_t k = 0; k < m.floats(); ++k)
      if (int(k % 16) < m.c) m.data[k] = f(k);
  };

  SECTION("a mask equal to the label scores 0, its complement nearly 1, nobody and no mask 0") {
    set_logits([&](std::size_t k) { return labels.mem[k] > 0.5f ? 40.f : -40.f; });
    CHECK(mask_loss(net, labels.act, dm.act, ds).dice == Approx(0).margin(1e-9));
    set_logits([&](std::size_t k) { return labels.mem[k] > 0.5f ? -40.f : 40.f; });
    // Each sample: 1 - 1 / (P + 1) (no overlap, the mask and the label cover the frame), or,
    // for sample 0 and 2 (nobody now, the mask everywhere), 1 - 1 / (P + 1) as well.
    CHECK(mask_loss(net, labels.act, dm.act, ds).dice == Approx(1 - 1.0 / (double(P) + 1)).epsilon(1e-9));
    // Half the blob found, nothing else: 1 - (2 B/2 + 1) / (B/2 + B + 1) for sample 1 alone.
    double blob = 0;
    for (std::size_t p = 0; p < P; ++p) blob += labels.mem[per + p * 16];
    std::size_t found = 0;
    set_logits([&](std::size_t k) {
      if (labels.mem[k] < 0.5f) return -40.f;
      return k / per == 1 && k % 16 == 0 && found++ % 2 == 0 ? 40.f : -40.f;
    });
    const double half = std::ceil(blob / 2), want = (1 - (2 * half + 1) / (half + blob + 1)) / 3;
    CHECK(mask_loss(net, labels.act, dm.act, ds).dice == Approx(want).epsilon(1e-9));
  }
  SECTION("weight 0 reports the term and leaves the loss and its gradient alone") {
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-3.f, 3.f);
    set_logits([&](std::size_t) { return u(rng); });
    const MaskLoss plain = mask_loss(net, labels.act, dm.act, ds);
    const std::vector<float> g0(dm.act.data, dm.act.data + dm.act.floats());
    CHECK(plain.dice > 0.1);
    CHECK(plain.total == Approx(plain.bce_first + plain.bce_all + plain.score_mse).epsilon(1e-12));
    const MaskLoss with = mask_loss(net, labels.act, dm.act, ds, {}, 2.0);
    CHECK(with.total == Approx(plain.total + 2.0 * plain.dice).epsilon(1e-12));
    std::size_t moved_now = 0, moved_later = 0;
    for (std::size_t k = 0; k < g0.size(); ++k)
      if (dm.act.data[k] != g0[k]) ++(k % 16 == 0 ? moved_now : moved_later);
    CHECK(moved_now > P);  // the current mask's logits of every sample
    CHECK(moved_later == 0);
    CHECK_THROWS_AS(mask_loss(net, labels.act, dm.act, ds, {}, -1.0), std::invalid_argument);
  }
  SECTION("the gradient of the loss with Dice, weighted samples, against central differences") {
    // The scores' targets (1 - mean |mask error|) are held fixed in the gradient, as a
    // target is: the finite differences leave the score term out.
    auto loss_of = [&] {
      const MaskLoss l = mask_loss(net, labels.act, dm.act, ds, {0.5f, 2.f, 1.f}, 3.0);
      return l.total - l.score_mse;
    };
    std::mt19937 rng(4);
    std::uniform_real_distribution<float> u(-3.f, 3.f);
    set_logits([&](std::size_t) { return u(rng); });
    const std::vector<float> w{0.5f, 2.f, 1.f};
    mask_loss(net, labels.act, dm.act, ds, w, 3.0);
    const std::vector<float> g(dm.act.data, dm.act.data + dm.act.floats());
    check_gradient_by_differences(m, g, 7, loss_of);
  }
}

TEST_CASE("mask loss: a focus K weighs future masks 1..K as the current one, gradient by finite differences",
          "[train][losses]") {
  const ModelConfig cfg = load_model_config("tiny");
  REQUIRE(cfg.n_masks >= 4);
  MaskNet net(cfg);
  net.init(6);
  net.set_training(false);
  test::Owned x(2, cfg.channels, cfg.height(), cfg.width(), 9);
  net.forward(x.act);
  const layers::Act& m = net.masks();
  const std::size_t per = m.floats() / 2, P = m.pixels();
  test::Owned labels(m);
  labels.for_each_real([&](std::size_t k) {
    const std::size_t c = k % 16, p = (k % per) / 16;
    labels.mem[k] = (p + 3 * c) % 23 < 8 ? 1.f : 0.f;  // a blob that moves from mask to mask
  });
  std::mt19937 rng(5);
  std::uniform_real_distribution<float> u(-3.f, 3.f);
  for (std::size_t k = 0; k < m.floats(); ++k)
    if (int(k % 16) < m.c) m.data[k] = u(rng);
  test::Owned dm(m);
  std::vector<float> ds;
  const MaskLoss plain = mask_loss(net, labels.act, dm.act, ds);
  const std::vector<float> g0(dm.act.data, dm.act.data + dm.act.floats());
  CHECK(plain.bce_focus == 0);
  const MaskLoss zero = mask_loss(net, labels.act, dm.act, ds, {}, 0, 0);
  CHECK(zero.total == plain.total);
  CHECK(std::vector<float>(dm.act.data, dm.act.data + dm.act.floats()) == g0);

  // Focus 2: the mean per-pixel BCE of masks 1 and 2 added, each as the current one's.
  const MaskLoss two = mask_loss(net, labels.act, dm.act, ds, {}, 0, 2);
  double want = 0;
  for (std::size_t k = 0; k < m.floats(); ++k) {
    const int c = int(k % 16);
    if (c < 1 || c > 2) continue;
    const double z = m.data[k], y = labels.mem[k];
    want += (std::max(z, 0.0) - z * y + std::log1p(std::exp(-std::abs(z)))) / double(2 * P);
  }
  CHECK(two.bce_focus == Approx(want).epsilon(1e-9));
  CHECK(two.total == Approx(plain.total + want).epsilon(1e-12));
  CHECK(two.bce_first == plain.bce_first);
  std::size_t moved_in = 0, moved_out = 0;
  for (std::size_t k = 0; k < g0.size(); ++k)
    if (dm.act.data[k] != g0[k]) ++((k % 16 == 1 || k % 16 == 2) ? moved_in : moved_out);
  CHECK(moved_in == 2 * 2 * P);
  CHECK(moved_out == 0);

  // The gradient with focus 3, against central differences (scores' targets held fixed).
  mask_loss(net, labels.act, dm.act, ds, {}, 0, 3);
  const std::vector<float> g(dm.act.data, dm.act.data + dm.act.floats());
  check_gradient_by_differences(m, g, 5, [&] {
    const MaskLoss l = mask_loss(net, labels.act, dm.act, ds, {}, 0, 3);
    return l.total - l.score_mse;
  });
  CHECK_THROWS_AS(mask_loss(net, labels.act, dm.act, ds, {}, 0, -1), std::invalid_argument);
  CHECK_THROWS_AS(mask_loss(net, labels.act, dm.act, ds, {}, 0, m.c), std::invalid_argument);
}

TEST_CASE("pose loss: --swap-loss scores each window against its joints or the mirror labelling, whichever is nearer",
          "[train][losses]") {
  const ModelConfig cfg = load_model_config("tiny");
  PoseNet net(cfg);
  net.init(5);
  net.set_training(false);
  const int S = cfg.window, n = 2 * S, J = cfg.joints;
  test::Owned x(n, cfg.channels, cfg.height(), cfg.width(), 31);
  net.forward(x.act, S);
  // The net's own joints as one labelling; traded left for right, the other (farther from
  // them wherever the net's left and right joints differ at all).
  std::vector<float> own(net.joints().begin(), net.joints().end()), traded(own.size()), valid(std::size_t(n) * J, 1.f);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < J; ++j)
      for (int c = 0; c < 3; ++c)
        traded[(std::size_t(i) * J + j) * 3 + c] = own[(std::size_t(i) * J + mirror_joint(j)) * 3 + c];
  // the second window's labels traded: it is scored against the other labelling
  std::vector<float> mixed(own);
  std::copy(traded.begin() + std::ptrdiff_t(S) * J * 3, traded.end(), mixed.begin() + std::ptrdiff_t(S) * J * 3);
  valid[5 * J + 8] = 0.f;  // a joint out of sight trades its validity with its mirror
  std::vector<float> mixed_valid(valid);
  for (int i = S; i < n; ++i)
    for (int j = 0; j < J; ++j) mixed_valid[std::size_t(i) * J + j] = valid[std::size_t(i) * J + mirror_joint(j)];
  std::vector<PoseNet::StageGrads> d_plain, d_swap;
  std::vector<layers::Floats> s_plain, s_swap;
  const HpeLoss plain = hpe_loss(net, cfg.stages, own.data(), mixed_valid.data(), d_plain, s_plain);
  const HpeLoss swap = hpe_loss(net, cfg.stages, mixed.data(), valid.data(), d_swap, s_swap, S);
  CHECK(swap.groups == 2);
  CHECK(swap.swapped == 1);
  CHECK(swap.total == Approx(plain.total).epsilon(1e-12));
  for (int t = 0; t < cfg.stages; ++t)
    for (int p = 0; p < 3; ++p)
      for (std::size_t i = 0; i < d_plain[t][p].floats(); ++i) REQUIRE(d_swap[t][p].data[i] == d_plain[t][p].data[i]);
  // without the option the traded window costs more; the mirror of a mirror is the joint
  const HpeLoss strict = hpe_loss(net, cfg.stages, mixed.data(), valid.data(), d_swap, s_swap);
  CHECK(strict.groups == 0);
  CHECK(strict.total > plain.total);
  for (int j = 0; j < J; ++j) CHECK(mirror_joint(mirror_joint(j)) == j);
  CHECK(mirror_joint(0) == 0);
  CHECK(mirror_joint(7) == 8);  // handR <-> handL
}

TEST_CASE("pose loss with pose.depth_map: z from the depth maps, the loss's gradient by finite differences", "[train][losses]") {
  const ModelConfig cfg = tiny_depth();
  PoseNet net(cfg);
  net.init(7);
  net.set_training(false);  // fixed BN statistics: the loss is a function of each weight alone
  const int S = cfg.window, J = cfg.joints;
  test::Owned x(S, cfg.channels, cfg.height(), cfg.width(), 13);
  std::vector<float> target(std::size_t(S) * J * 3), valid(std::size_t(S) * J, 1.f);
  for (std::size_t i = 0; i < target.size(); ++i) target[i] = float(0.6 * std::sin(1.3 * double(i) + 0.4));
  valid[3] = 0.f;
  std::vector<PoseNet::StageGrads> dheat;
  std::vector<layers::Floats> store;
  layers::ParamList params;
  net.params(params);
  // The loss scaled so that the finite differences' tolerance, absolute for small
  // gradients, is relative for these: a missing path through the depth maps shows.
  constexpr double kScale = 50;
  auto loss = [&] {
    net.weights_changed();
    net.forward(x.act, S);
    return kScale * hpe_loss(net, cfg.stages, target.data(), valid.data(), dheat, store).total;
  };
  for (auto& p : params)
    if (p.param->trainable) p.param->grad.zero();
  loss();
  for (int t = 0; t < cfg.stages; ++t) REQUIRE(dheat[std::size_t(t)][3].data != nullptr);
  net.backward(x.act, dheat, nullptr);
  for (auto& p : params)
    if (p.param->trainable)
      for (std::size_t i = 0; i < p.param->numel(); ++i) p.param->grad.data()[i] *= float(kScale);
  int checked = 0, layer = 0;
  for (auto& p : params) {
    if (!p.param->trainable || p.param->shape.size() != 4) continue;
    const bool depth = p.key.rfind("depth_hm_cnns.", 0) == 0, xy = p.key.rfind("xy_hm_cnns.", 0) == 0;
    if (!((depth || xy) && layer++ % 6 == 0)) continue;
    INFO(p.key);
    checked += test::check_fd_kinked(loss, p.param->value.data(), p.param->grad.data(),
                                     test::sample_all(p.param->numel(), p.param->numel() / 3 + 1), 1e-2, 1e-2, p.key.c_str(), 0.0);
  }
  CHECK(checked >= 8);
  // The zy and xz maps no longer carry z: moving a depth map moves the loss, the joints' z with it.
  net.forward(x.act, S);
  std::vector<float> z0(net.joints());
  layers::Act dm = *net.depth_map(cfg.stages - 1);
  for (std::size_t i = 0; i < dm.floats(); ++i) dm.data[i] += 0.25f;
  std::vector<float> moved(z0.size());
  net.stage_joints(cfg.stages - 1, moved.data());
  for (std::size_t k = 0; k < z0.size(); k += 3) {
    CHECK(moved[k] == z0[k]);
    CHECK(moved[k + 2] == Approx(z0[k + 2] + 0.25).margin(1e-5));
  }
}

TEST_CASE("a plain pose net's weights start one with pose.depth_map (yelan train --init)", "[train][losses]") {
  const ModelConfig base = load_model_config("tiny");
  const ModelConfig cfg = tiny_depth();
  PoseNet deep(cfg), plain(base);
  layers::ParamList pd, pp;
  deep.params(pd);
  plain.params(pp);
  REQUIRE(pd.size() > pp.size());
  // Every shared tensor taken, the depth hourglasses kept as they were; without the
  // allowance (or with another prefix) the file does not fit.
  plain.init(9);
  deep.init(4);
  weights::Weights w;
  w.groups["pose"] = weights::group_of(pp);
  const std::vector<float> kept(pd.back().param->value.data(), pd.back().param->value.data() + pd.back().param->numel());
  CHECK_THROWS_WITH(weights::load_group(w, "pose", pd, "plain.h5"), Catch::Contains("missing: depth_hm_cnns.0."));
  CHECK_THROWS_WITH(weights::load_group(w, "pose", pd, "plain.h5", "xy_hm_cnns."), Catch::Contains("missing: depth_hm_cnns.0."));
  CHECK(weights::load_group(w, "pose", pd, "plain.h5", "depth_hm_cnns.") == pd.size() - pp.size());
  for (std::size_t i = 0; i < pp.size(); ++i) {
    INFO(pp[i].key);
    REQUIRE(pd[i].key == pp[i].key);
    REQUIRE(std::equal(pp[i].param->value.data(), pp[i].param->value.data() + pp[i].param->numel(), pd[i].param->value.data()));
  }
  CHECK(std::equal(kept.begin(), kept.end(), pd.back().param->value.data()));
  CHECK(weights::load_group(w, "pose", pp, "plain.h5") == 0);
}
