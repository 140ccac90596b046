// The pixel model's formulas against hand-computed values: lin-log, the low-pass, ESIM
// crossing times, refractory, ordering, determinism across threads, bad input.
#include <omp.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "camera/sim/pixel_model.h"

using yelan::camera::Event;
using namespace yelan::camera::sim;

namespace {

std::vector<float> flat(int w, int h, float v) { return std::vector<float>(std::size_t(w) * h, v); }

// An ideal pixel with exact nominal thresholds: the crossing arithmetic is then by hand.
PixelParams ideal(double on = 0.2, double off = 0.2) {
  PixelParams p = pixel_params_clean();
  p.pos_threshold = on;
  p.neg_threshold = off;
  return p;
}

}  // namespace

TEST_CASE("pixel lin-log is linear below the knee, log above, continuous at it") {
  // Below: I * ln(20) / 20; above: ln(I).
  CHECK(lin_log(10, 20) == Approx(1.4978661367769954).epsilon(1e-12));
  CHECK(lin_log(0, 20) == 0.0);
  CHECK(lin_log(100, 20) == Approx(4.605170185988092).epsilon(1e-12));
  CHECK(lin_log(20, 20) == Approx(2.995732273553991).epsilon(1e-12));
  CHECK(lin_log(20 * (1 + 1e-9), 20) == Approx(lin_log(20 * (1 - 1e-9), 20)).epsilon(1e-8));

  // The model's vector path gives the same values; bad intensities count as dark.
  const std::vector<float> in = {0, 10, 20, 100, 255, -5, NAN, INFINITY, 20.5f};
  PixelModel m(int(in.size()), 1, pixel_params_clean(), 1);
  m.reset(in.data(), 0);
  CHECK(m.filtered_log(0, 0) == 0.f);
  CHECK(m.filtered_log(1, 0) == Approx(1.4978661367769954).epsilon(1e-6));
  CHECK(m.filtered_log(2, 0) == Approx(2.995732273553991).epsilon(1e-6));
  CHECK(m.filtered_log(3, 0) == Approx(4.605170185988092).epsilon(1e-6));
  CHECK(m.filtered_log(4, 0) == Approx(std::log(255.0)).epsilon(1e-6));
  CHECK(m.filtered_log(5, 0) == 0.f);
  CHECK(m.filtered_log(6, 0) == 0.f);
  CHECK(m.filtered_log(7, 0) == Approx(std::log(1e9)).epsilon(1e-6));  // capped, finite
  CHECK(m.filtered_log(8, 0) == Approx(std::log(20.5)).epsilon(1e-6));
}

TEST_CASE("pixel low-pass step matches the first-order closed form") {
  PixelParams p = pixel_params_clean();
  p.cutoff_hz = 300;
  p.cutoff_floor_dn = 20;
  // Bright pixel 100 -> 200 over 1 ms: cutoff 300 * (200 + 20) / 275 = 240 Hz,
  // alpha = 1 - exp(-0.001 * 2 pi * 240) = 1 - exp(-1.507964) = 0.778640.
  CHECK(lowpass_alpha(200, 1e-3, p) == Approx(0.7786398960093939).epsilon(1e-12));
  // Dark pixel 2 -> 4: cutoff 300 * 24 / 275 = 26.18 Hz, alpha = 0.151687 (slower).
  CHECK(lowpass_alpha(4, 1e-3, p) == Approx(0.1516866672886561).epsilon(1e-12));
  p.cutoff_hz = 0;
  CHECK(lowpass_alpha(4, 1e-3, p) == 1.0);
  p.cutoff_hz = 300;

  std::vector<float> a = {100, 2, 100}, b = {200, 4, 100};
  PixelModel m(3, 1, p, 7);
  m.reset(a.data(), 0);
  std::vector<Event> ev;
  m.step(b.data(), 0, 1e-3, ev);
  // ln100 + alpha (ln200 - ln100) = 5.144882; linear region: 2c + alpha_dark (4c - 2c) with
  // c = ln(20)/20, = 0.345014.
  CHECK(m.filtered_log(0, 0) == Approx(5.144882234578492).epsilon(2e-6));
  CHECK(m.filtered_log(1, 0) == Approx(0.34501449182184646).epsilon(2e-6));
  CHECK(m.filtered_log(2, 0) == Approx(4.605170185988092).epsilon(1e-6));
  // A second step at the same input closes the gap by (1 - alpha) again:
  // ln200 - ln2 (1 - alpha)^2 = 5.264353.
  m.step(b.data(), 1e-3, 2e-3, ev);
  CHECK(m.filtered_log(0, 0) == Approx(5.264352949779446).epsilon(2e-6));
  // The filtered change (0.54 then 0.12) made ON events, none from the constant pixel.
  for (const Event& e : ev) CHECK(e.x != 2);
}

TEST_CASE("pixel step of 2.5 thresholds gives two ON events at interpolated times") {
  const int w = 7, h = 5;
  PixelModel m(w, h, ideal(), 3);
  auto a = flat(w, h, 100), b = a;
  b[2 * w + 3] = float(100 * std::exp(0.5));  // +0.5 = 2.5 thresholds of 0.2
  m.reset(a.data(), 0.010);
  std::vector<Event> ev;
  m.step(b.data(), 0.010, 0.011, ev);
  // Crossings at 0.2/0.5 and 0.4/0.5 of the 1 ms step: 10400 and 10800 us.
  REQUIRE(ev.size() == 2);
  CHECK(ev[0] == Event{10400, 3, 2, 1});
  CHECK(ev[1] == Event{10800, 3, 2, 1});
  CHECK(m.log_minus_reference(3, 2) == Approx(0.1).epsilon(1e-4));
  // Another +0.15: diff goes 0.1 -> 0.25 and crosses 0.2 a third of the way... at
  // (0.2 - 0.1) / 0.15 = 2/3 of the step: 11000 + 666.7 -> 11667 us.
  auto c = b;
  c[2 * w + 3] = float(100 * std::exp(0.65));
  ev.clear();
  m.step(c.data(), 0.011, 0.012, ev);
  REQUIRE(ev.size() == 1);
  CHECK(ev[0] == Event{11667, 3, 2, 1});
  CHECK(m.log_minus_reference(3, 2) == Approx(0.05).epsilon(1e-3));
  CHECK(m.stats().signal == 3);
}

TEST_CASE("pixel step of -2.5 OFF thresholds gives two OFF events at interpolated times") {
  const int w = 5, h = 3;
  PixelModel m(w, h, ideal(0.2, 0.25), 3);
  auto a = flat(w, h, 100), b = a;
  b[1 * w + 4] = float(100 * std::exp(-0.625));  // -2.5 OFF thresholds of 0.25
  m.reset(a.data(), 2.0);
  std::vector<Event> ev;
  m.step(b.data(), 2.0, 2.002, ev);
  // Crossings at 0.25/0.625 = 0.4 and 0.8 of a 2 ms step: +800 and +1600 us.
  REQUIRE(ev.size() == 2);
  CHECK(ev[0] == Event{2000800, 4, 1, 0});
  CHECK(ev[1] == Event{2001600, 4, 1, 0});
  CHECK(m.log_minus_reference(4, 1) == Approx(-0.125).epsilon(1e-4));
}

TEST_CASE("pixel refractory period drops a crossing inside it") {
  PixelParams p = ideal();
  p.refractory_s = 0.0005;  // the two crossings are 0.4 ms apart
  const int w = 3, h = 3;
  auto a = flat(w, h, 100), b = a;
  b[4] = float(100 * std::exp(0.5));
  PixelModel m(w, h, p, 3);
  m.reset(a.data(), 0.010);
  std::vector<Event> ev;
  m.step(b.data(), 0.010, 0.011, ev);
  REQUIRE(ev.size() == 1);
  CHECK(ev[0] == Event{10400, 1, 1, 1});
  CHECK(m.stats().refractory_dropped == 1);
  // The dropped crossing still moved the reference: the change was absorbed.
  CHECK(m.log_minus_reference(1, 1) == Approx(0.1).epsilon(1e-4));

  p.refractory_s = 0.0003;  // shorter than the gap: both pass
  PixelModel m2(w, h, p, 3);
  m2.reset(a.data(), 0.010);
  ev.clear();
  m2.step(b.data(), 0.010, 0.011, ev);
  CHECK(ev.size() == 2);
}

TEST_CASE("pixel event count and times do not depend on the step size") {
  // A log ramp of +2.1 over 10 ms (10.5 thresholds): one step or 10 give the same crossings,
  // at (k * 0.2 / 2.1) * 10 ms.
  const int w = 3, h = 2;
  auto a = flat(w, h, 50);
  std::vector<Event> one, ten;
  PixelModel m1(w, h, ideal(), 5), m10(w, h, ideal(), 5);
  m1.reset(a.data(), 0);
  m10.reset(a.data(), 0);
  auto at = [&](double t) {
    auto f = a;
    f[5] = float(50 * std::exp(2.1 * t / 0.01));
    return f;
  };
  auto end = at(0.01);
  m1.step(end.data(), 0, 0.01, one);
  for (int k = 0; k < 10; ++k) {
    auto f = at((k + 1) * 1e-3);
    m10.step(f.data(), k * 1e-3, (k + 1) * 1e-3, ten);
  }
  REQUIRE(one.size() == 10);
  REQUIRE(ten.size() == 10);
  for (int k = 0; k < 10; ++k) {
    const double expect_us = (k + 1) * 0.2 / 2.1 * 1e4;
    CHECK(std::abs(double(one[k].t) - expect_us) <= 1.0);
    CHECK(std::abs(double(ten[k].t) - expect_us) <= 1.0);
    CHECK(one[k].x == 2);
    CHECK(one[k].y == 1);
  }
}

TEST_CASE("pixel constant scene with all noise off makes no events") {
  const int w = 37, h = 29;  // odd sizes, values across the knee
  std::vector<float> f(std::size_t(w) * h);
  for (std::size_t i = 0; i < f.size(); ++i) f[i] = float((i * 37) % 300) * 0.9f;
  for (double cutoff : {0.0, 300.0}) {
    PixelParams p = pixel_params_clean();
    p.sigma_threshold = 0.03;
    p.cutoff_hz = cutoff;
    PixelModel m(w, h, p, 11);
    m.reset(f.data(), 0);
    std::vector<Event> ev;
    for (int k = 0; k < 2000; ++k) m.step(f.data(), k * 1e-3, (k + 1) * 1e-3, ev);
    CHECK(ev.empty());
  }
}

namespace {

// A bright bar sweeping right over a textured, flickering-free background.
std::vector<float> moving_scene(int w, int h, int k) {
  std::vector<float> f(std::size_t(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const bool bar = ((x - 2 * k) % 97 + 97) % 97 < 20;
      f[std::size_t(y) * w + x] = bar ? 240.f : 15.f + float((x * 7 + y * 3) % 40);
    }
  return f;
}

std::vector<Event> run_scene(int w, int h, const PixelParams& p, int steps) {
  PixelModel m(w, h, p, 1234);
  auto f0 = moving_scene(w, h, 0);
  m.reset(f0.data(), 0);
  std::vector<Event> ev;
  for (int k = 1; k <= steps; ++k) {
    auto f = moving_scene(w, h, k);
    m.step(f.data(), (k - 1) * 1e-3, k * 1e-3, ev);
  }
  return ev;
}

PixelParams all_noise() {
  PixelParams p;  // DAVIS defaults, noise turned up so every source shows
  p.shot_noise_rate_hz = 20;
  p.leak_rate_hz = 2;
  p.hot_pixel_fraction = 1e-3;
  return p;
}

}  // namespace

TEST_CASE("pixel events are sorted by time, then row, then column, inside each step") {
  const int w = 131, h = 47;
  const auto ev = run_scene(w, h, all_noise(), 40);
  REQUIRE(ev.size() > 1000);
  std::size_t same_time = 0;
  for (std::size_t i = 1; i < ev.size(); ++i) {
    const Event &a = ev[i - 1], &b = ev[i];
    const bool ordered =
        a.t < b.t || (a.t == b.t && (a.y < b.y || (a.y == b.y && a.x <= b.x)));
    if (!ordered) FAIL("events " << i - 1 << " and " << i << " out of order");
    same_time += a.t == b.t;
  }
  CHECK(same_time > 0);  // the tie-break was exercised
  for (const Event& e : ev) {
    CHECK(e.t > 0);
    CHECK(e.t <= 40000);
    CHECK(e.x < w);
    CHECK(e.y < h);
  }
}

TEST_CASE("pixel results are identical with one and two threads") {
  const int w = 346, h = 260;
  const int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  const auto one = run_scene(w, h, all_noise(), 12);
  omp_set_num_threads(2);
  const auto two = run_scene(w, h, all_noise(), 12);
  omp_set_num_threads(saved);
  REQUIRE(one.size() > 10000);
  REQUIRE(one.size() == two.size());
  // Field by field: Event has padding bytes, which carry no data.
  CHECK(one == two);
}

TEST_CASE("pixel max_log_change bounds the next step's largest change") {
  const int w = 9, h = 4;
  auto a = flat(w, h, 100), b = a;
  PixelModel m(w, h, ideal(), 1);
  m.reset(a.data(), 0);
  CHECK(m.max_log_change(a.data()) == 0.0);
  b[3 * w + 8] = float(100 * std::exp(-0.7));
  b[0] = 110;
  CHECK(m.max_log_change(b.data()) == Approx(0.7).epsilon(1e-5));
}

TEST_CASE("pixel rejects bad sizes, parameters and times") {
  CHECK_THROWS_AS(PixelModel(0, 5, PixelParams{}, 1), std::invalid_argument);
  CHECK_THROWS_AS(PixelModel(70000, 5, PixelParams{}, 1), std::invalid_argument);
  PixelParams p;
  p.pos_threshold = -0.1;
  CHECK_THROWS_AS(PixelModel(4, 4, p, 1), std::invalid_argument);
  p = PixelParams{};
  p.cutoff_hz = NAN;
  CHECK_THROWS_AS(PixelModel(4, 4, p, 1), std::invalid_argument);
  p = PixelParams{};
  p.hot_pixel_fraction = 2;
  CHECK_THROWS_AS(PixelModel(4, 4, p, 1), std::invalid_argument);

  PixelModel m(4, 4, PixelParams{}, 1);
  auto f = flat(4, 4, 50);
  std::vector<Event> ev;
  CHECK_THROWS_AS(m.step(f.data(), 0, 1e-3, ev), std::logic_error);  // before reset
  m.reset(f.data(), 0);
  CHECK_THROWS_AS(m.step(f.data(), 1e-3, 1e-3, ev), std::invalid_argument);
  CHECK_THROWS_AS(m.step(f.data(), 2e-3, 1e-3, ev), std::invalid_argument);
  CHECK_THROWS_AS(m.step(f.data(), 0, INFINITY, ev), std::invalid_argument);
  CHECK_THROWS_AS(m.step(nullptr, 0, 1e-3, ev), std::invalid_argument);
  // Absurd intensities are clamped, not crashed on, and yield a bounded burst.
  auto g = f;
  g[0] = INFINITY;
  g[1] = NAN;
  g[2] = -1e30f;
  g[3] = 1e38f;
  m.step(g.data(), 0, 1e-3, ev);
  CHECK(ev.size() < 2000);
}
