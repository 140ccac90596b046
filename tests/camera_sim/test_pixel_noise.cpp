// Statistics of the pixel model's random parts: threshold mismatch, leak, shot noise and
// hot pixels, measured over seconds of static scenes against the rates that were set.
#include <catch2/catch.hpp>
#include <cmath>
#include <set>
#include <vector>

#include "camera/sim/pixel_model.h"

using yelan::camera::Event;
using namespace yelan::camera::sim;

namespace {

constexpr int kW = 101, kH = 73;  // odd sizes; 7373 pixels

// Noise-free, mismatch-free settings; each test switches on the one source it measures.
PixelParams quiet() {
  PixelParams p = pixel_params_clean();
  p.cutoff_hz = 300;
  return p;
}

// Runs a static scene of constant intensity for `seconds` in steps of `dt`.
std::vector<Event> run_static(const PixelParams& p, float intensity, double seconds, double dt,
                              std::uint64_t seed = 99) {
  std::vector<float> f(std::size_t(kW) * kH, intensity);
  PixelModel m(kW, kH, p, seed);
  m.reset(f.data(), 0);
  std::vector<Event> ev;
  const int steps = int(std::lround(seconds / dt));
  for (int k = 0; k < steps; ++k) m.step(f.data(), k * dt, (k + 1) * dt, ev);
  return ev;
}

double rate_per_pixel(const std::vector<Event>& ev, double seconds) {
  return double(ev.size()) / (double(kW) * kH * seconds);
}

}  // namespace

TEST_CASE("pixel threshold mismatch has the set mean and spread") {
  PixelParams p;
  p.pos_threshold = 0.2;
  p.neg_threshold = 0.3;
  p.sigma_threshold = 0.03;
  const int w = 346, h = 260;
  PixelModel m(w, h, p, 5);
  double s_on = 0, s2_on = 0, s_off = 0, s2_off = 0, s_cross = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double a = m.threshold_on(x, y), b = m.threshold_off(x, y);
      s_on += a, s2_on += a * a, s_off += b, s2_off += b * b, s_cross += a * b;
    }
  const double n = double(w) * h;
  const double mean_on = s_on / n, mean_off = s_off / n;
  const double sd_on = std::sqrt(s2_on / n - mean_on * mean_on);
  const double sd_off = std::sqrt(s2_off / n - mean_off * mean_off);
  // Standard error of the mean is 0.03 / 300 = 1e-4; of the sd about 0.2%.
  CHECK(std::abs(mean_on - 0.2) < 5e-4);
  CHECK(std::abs(mean_off - 0.3) < 5e-4);
  CHECK(std::abs(sd_on - 0.03) < 0.03 * 0.02);
  CHECK(std::abs(sd_off - 0.03) < 0.03 * 0.02);
  // ON and OFF are drawn independently.
  const double corr = (s_cross / n - mean_on * mean_off) / (sd_on * sd_off);
  CHECK(std::abs(corr) < 0.02);

  // A wide spread is clipped at 0.01, never below.
  p.pos_threshold = 0.05;
  p.sigma_threshold = 0.1;
  PixelModel wide(w, h, p, 5);
  int clipped = 0;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      CHECK(wide.threshold_on(x, y) >= 0.01f);
      clipped += wide.threshold_on(x, y) == 0.01f;
    }
  CHECK(clipped > 0.25 * n);  // P(N(0.05, 0.1) < 0.01) = 0.34
}

TEST_CASE("pixel leak rate over 10 s of a static scene is within 10% of the set rate") {
  for (double rate : {0.1, 1.0}) {
    PixelParams p = quiet();
    p.sigma_threshold = 0.03;
    p.leak_rate_hz = rate;
    p.refractory_s = 0.0005;
    const auto ev = run_static(p, 120, 10.0, 5e-3);
    const double measured = rate_per_pixel(ev, 10.0);
    INFO("set " << rate << " Hz, measured " << measured << " Hz");
    CHECK(std::abs(measured - rate) < 0.1 * rate);
    // Leak only raises the pixel above its reference: ON events, spread over the run
    // (random phases), not a burst at the start.
    std::vector<int> per_second(10, 0);
    for (const Event& e : ev) {
      CHECK(e.p == 1);
      ++per_second[std::min<std::size_t>(9, std::size_t(e.t / 1000000))];
    }
    for (int s = 0; s < 10; ++s) {
      CHECK(per_second[s] > 0.05 * double(ev.size()));
      CHECK(per_second[s] < 0.15 * double(ev.size()));
    }
  }
}

TEST_CASE("pixel shot noise rate rises as light falls") {
  PixelParams p = quiet();
  p.shot_noise_rate_hz = 1.0;
  p.shot_noise_bright_factor = 0.25;
  const double dt = 5e-3;
  const auto dark = run_static(p, 0, 10.0, dt);
  const auto low = run_static(p, 4, 10.0, dt);
  const auto medium = run_static(p, 60, 10.0, dt);
  const auto bright = run_static(p, 255, 10.0, dt);
  const double r_dark = rate_per_pixel(dark, 10), r_low = rate_per_pixel(low, 10);
  const double r_med = rate_per_pixel(medium, 10), r_bright = rate_per_pixel(bright, 10);
  INFO("dark " << r_dark << " low " << r_low << " medium " << r_med << " bright " << r_bright);
  // Set rates: 1 at 0 DN, 1 - 0.75 * I / 255: 0.9882 at 4, 0.8235 at 60, 0.25 at 255.
  // About 73730 dark events: Poisson sd 0.4%.
  CHECK(std::abs(r_dark - 1.0) < 0.03);
  CHECK(std::abs(r_low - 0.98824) < 0.03);
  CHECK(std::abs(r_med - 0.82353) < 0.03);
  CHECK(std::abs(r_bright - 0.25) < 0.02);
  CHECK(r_dark > r_med);
  CHECK(r_med > r_bright);
  CHECK(shot_noise_rate(0, p) == 1.0);
  CHECK(shot_noise_rate(60, p) == Approx(0.8235294117647058));
  CHECK(shot_noise_rate(1000, p) == Approx(0.25));

  // Half ON, half OFF, and uniform inside each 5 ms step rather than at its end.
  std::size_t on = 0, at_end = 0;
  double phase = 0;
  for (const Event& e : dark) {
    on += e.p;
    at_end += e.t % 5000 == 0;
    phase += double(e.t % 5000) / 5000;
  }
  const double n = double(dark.size());
  CHECK(std::abs(on / n - 0.5) < 0.02);
  CHECK(at_end < 0.01 * n);
  CHECK(std::abs(phase / n - 0.5) < 0.01);

  // With threshold mismatch the dark rate stays near the set rate (v2e scales each pixel's
  // rate by nominal / actual threshold, which averages slightly above 1).
  p.sigma_threshold = 0.03;
  const double r_mis = rate_per_pixel(run_static(p, 0, 10.0, dt), 10);
  CHECK(std::abs(r_mis - 1.0) < 0.05);
}

TEST_CASE("pixel noise rates do not depend on the step size") {
  PixelParams p = quiet();
  p.shot_noise_rate_hz = 2.0;
  p.leak_rate_hz = 0.5;
  const double fine = rate_per_pixel(run_static(p, 30, 4.0, 1e-3), 4.0);
  const double coarse = rate_per_pixel(run_static(p, 30, 4.0, 8e-3), 4.0);
  INFO("1 ms steps " << fine << " Hz, 8 ms steps " << coarse << " Hz");
  // Expected 2 * (1 - 0.75 * 30/255) + 0.5 = 2.324 Hz; Poisson sd about 0.4%.
  CHECK(std::abs(fine - 2.3235) < 0.05);
  CHECK(std::abs(coarse - 2.3235) < 0.05);
}

TEST_CASE("pixel hot pixels are a fixed set firing near their rate") {
  PixelParams p = quiet();
  p.hot_pixel_fraction = 0.01;
  p.hot_pixel_rate_hz = 50;
  PixelModel a(kW, kH, p, 42), b(kW, kH, p, 42), c(kW, kH, p, 43);
  std::set<int> hot_a, hot_c;
  for (int y = 0; y < kH; ++y)
    for (int x = 0; x < kW; ++x) {
      CHECK(a.is_hot(x, y) == b.is_hot(x, y));
      if (a.is_hot(x, y)) hot_a.insert(y * kW + x);
      if (c.is_hot(x, y)) hot_c.insert(y * kW + x);
    }
  CHECK(hot_a.size() == a.hot_pixel_count());
  // 7373 * 1% = 74 expected (sd 8.6).
  CHECK(hot_a.size() > 45);
  CHECK(hot_a.size() < 105);
  CHECK(hot_a != hot_c);

  const auto ev = run_static(p, 100, 10.0, 5e-3, 42);
  std::vector<int> count(std::size_t(kW) * kH, 0);
  for (const Event& e : ev) {
    CHECK(e.p == 1);
    ++count[std::size_t(e.y) * kW + e.x];
  }
  double total = 0;
  for (int i = 0; i < kW * kH; ++i) {
    if (!hot_a.count(i)) {
      CHECK(count[i] == 0);  // nothing else makes events here
      continue;
    }
    total += count[i];
    // 500 expected per pixel in 10 s, refractory 0 here; Poisson sd 22.
    CHECK(count[i] > 400);
    CHECK(count[i] < 600);
  }
  const double mean_rate = total / (double(hot_a.size()) * 10);
  CHECK(std::abs(mean_rate - 50) < 2.5);
}

TEST_CASE("pixel noise clocks stay exact over long runs") {
  // 300 s in 0.1 s steps: the shot clocks are rebased every 64 s; the rate must not drift
  // and every event must stay inside its step.
  PixelParams p = quiet();
  p.shot_noise_rate_hz = 1.0;
  p.leak_rate_hz = 0.2;
  std::vector<float> f(std::size_t(kW) * kH, 0.f);
  PixelModel m(kW, kH, p, 8);
  m.reset(f.data(), 1000.0);  // a late start: absolute times do not matter
  std::vector<double> per_100s(3, 0);
  std::vector<Event> ev;
  for (int k = 0; k < 3000; ++k) {
    ev.clear();
    const double t0 = 1000.0 + k * 0.1, t1 = t0 + 0.1;
    m.step(f.data(), t0, t1, ev);
    for (const Event& e : ev) {
      if (e.t <= std::llround(t0 * 1e6) || e.t > std::llround(t1 * 1e6)) FAIL("event outside step " << k);
    }
    per_100s[k / 1000] += double(ev.size());
  }
  for (double n : per_100s) {
    const double rate = n / (double(kW) * kH * 100);
    INFO("rate " << rate << " Hz (expected 1.2)");
    CHECK(std::abs(rate - 1.2) < 0.02);
  }
}
