// The mask loss's sample weights: a weighted mean of what each sample alone would give, and
// the windows with nobody in their current frame found from the labels.
#include <catch2/catch.hpp>

#include <cmath>

#include "engine/losses.h"
#include "engine/model_config.h"
#include "layer_fd.h"

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
