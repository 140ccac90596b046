#include <catch2/catch.hpp>

#include <cmath>
#include <random>
#include <stdexcept>
#include <vector>

#include "camera/repr/fast_log.h"
#include "camera/repr/tore.h"
#include "test_util.h"

using yelan::camera::BaldwinScale;
using yelan::camera::Event;
using yelan::camera::PixelRect;
using yelan::camera::ToreOptions;
using yelan::camera::ToreVolume;

namespace {

// Volume element (channel c, row y, column x) of a channel-major read-out.
float at(const std::vector<float>& v, const ToreVolume& t, int c, int y, int x) {
  return v[(std::size_t(c) * t.height() + y) * t.width() + x];
}

std::vector<float> read(const ToreVolume& t, std::int64_t when) {
  std::vector<float> v(t.volume_size(), -1.f);
  t.readout(when, v.data());
  return v;
}

}  // namespace

TEST_CASE("fast_ln stays within its stated error of std::log", "[tore]") {
  double max_abs = 0, max_ulp = 0;
  for (float x = 1.f / 16; x <= 2147483648.f;) {
    const double ref = std::log(double(x));
    const double err = std::fabs(double(yelan::camera::fast_ln(x)) - ref);
    max_abs = std::max(max_abs, err);
    if (std::fabs(ref) > 1e-3) {
      const float r = float(std::fabs(ref));
      max_ulp = std::max(max_ulp, err / double(std::nextafter(r, 1e30f) - r));
    }
    for (int i = 0; i < 997; ++i) x = std::nextafter(x, 1e30f);  // a prime stride of floats
  }
  CHECK(max_abs <= 1.1e-6);
  CHECK(max_ulp <= 3.0);
  // exact points
  CHECK(yelan::camera::fast_ln(1.f) == 0.f);
  CHECK(yelan::camera::fast_ln(2.f) == Approx(0.6931471805599453).epsilon(1e-7));
  CHECK(yelan::camera::fast_ln(5e6f) == Approx(15.424948470398375).epsilon(2e-7));
}

TEST_CASE("TORE keeps the K newest stamps per pixel and polarity, newest first", "[tore]") {
  ToreVolume tore(5, 3);  // odd sizes; K = 3
  REQUIRE(tore.channels() == 6);
  REQUIRE(tore.volume_size() == 6u * 5 * 3);
  for (std::int64_t t : {100, 200, 300, 400}) tore.update(Event{t, 2, 1, 1});
  tore.update(Event{1000, 4, 2, 0});
  CHECK(tore.slot(2, 1, 1, 0) == 400);
  CHECK(tore.slot(2, 1, 1, 1) == 300);
  CHECK(tore.slot(2, 1, 1, 2) == 200);  // 100 fell out of the FIFO
  CHECK(tore.slot(2, 1, 0, 0) == ToreVolume::kEmpty);
  CHECK(tore.slot(4, 2, 0, 0) == 1000);
  CHECK(tore.slot(4, 2, 0, 1) == ToreVolume::kEmpty);
}

TEST_CASE("TORE read-out matches hand-computed YeLan values", "[tore]") {
  ToreVolume tore(5, 3);
  for (std::int64_t t : {100, 200, 300, 400}) tore.update(Event{t, 2, 1, 1});
  tore.update(Event{1000, 4, 2, 0});
  const auto v = read(tore, 1100);
  // pos slots of (2, 1): ages 700, 800, 900 us; value = clamp(1 - ln(1+a)/ln(5e6), 0, .7)/.7
  CHECK(at(v, tore, 0, 1, 2) == Approx(0.8217152325).margin(2e-6));
  CHECK(at(v, tore, 1, 1, 2) == Approx(0.8093648268).margin(2e-6));
  CHECK(at(v, tore, 2, 1, 2) == Approx(0.7984692766).margin(2e-6));
  // neg0 of (4, 2): age 100 us is inside the clamp (ages up to ~101.3 us read 1)
  CHECK(at(v, tore, 3, 2, 4) == 1.f);
  CHECK(at(v, tore, 4, 2, 4) == 0.f);  // empty
  int nonzero = 0;
  for (float x : v) nonzero += x != 0.f;
  CHECK(nonzero == 4);
  // age 102 us is just past the clamp, age 999 us reads 0.78881
  CHECK(read(tore, 1102)[(3 * 3 + 2) * 5 + 4] == Approx(0.9993290603).margin(2e-6));
  CHECK(read(tore, 1999)[(3 * 3 + 2) * 5 + 4] == Approx(0.7888142296).margin(2e-6));
}

TEST_CASE("TORE read-out: ages at or past tau, and events newer than T, read 0", "[tore]") {
  ToreVolume tore(1, 1, ToreOptions{2, 1000});  // K = 2, tau = 1000 us
  tore.update(Event{5000, 0, 0, 1});
  tore.update(Event{6000, 0, 0, 1});
  auto v = read(tore, 6998);  // ages 998 and 1998: (1 - ln(999)/ln(1000)) / 0.7 = 2.07e-4
  CHECK(v[0] == Approx((1 - std::log(999.0) / std::log(1000.0)) / 0.7).margin(2e-6));
  CHECK(v[0] > 1e-4f);
  CHECK(v[1] == 0.f);
  CHECK(read(tore, 6999)[0] == Approx(0.0).margin(2e-6));  // age 999: ln(1 + 999) = ln(tau)
  v = read(tore, 7000);  // age == tau
  CHECK(v[0] == 0.f);
  // T before the newest event: slot 0 has not arrived and reads 0; slot 1 (age 500) does not move up
  v = read(tore, 5500);
  CHECK(v[0] == 0.f);
  const double expect = std::clamp(1 - std::log1p(500.0) / std::log(1000.0), 0.0, 0.7) / 0.7;
  CHECK(v[1] == Approx(expect).margin(2e-6));
  // age 0 (an event exactly at T) reads 1
  CHECK(read(tore, 6000)[0] == 1.f);
  CHECK(read(tore, 6000)[1] == 0.f);  // age 1000 == tau
}

TEST_CASE("TORE read-out of a rectangle equals the whole read-out there and leaves the rest", "[tore]") {
  ToreVolume tore(37, 23, ToreOptions{3, 5'000'000});
  std::mt19937 rng(11);
  for (int i = 0; i < 4000; ++i)
    tore.update(Event{std::int64_t(i) * 97, std::uint16_t(rng() % 37), std::uint16_t(rng() % 23), std::uint8_t(rng() % 2)});
  const std::int64_t T = 4000 * 97;
  const auto full = read(tore, T);
  for (PixelRect r : {PixelRect{5, 3, 29, 17}, PixelRect{-4, -2, 9, 40}, PixelRect{30, 0, 99, 1}, PixelRect{0, 0, 37, 23},
                      PixelRect{12, 12, 12, 20}}) {
    std::vector<float> v(tore.volume_size(), -7.f);
    tore.readout(T, v.data(), r);
    int inside = 0, nonzero = 0;
    for (int c = 0; c < tore.channels(); ++c)
      for (int y = 0; y < 23; ++y)
        for (int x = 0; x < 37; ++x) {
          const std::size_t i = (std::size_t(c) * 23 + y) * 37 + x;
          const bool in = x >= r.x0 && x < r.x1 && y >= r.y0 && y < r.y1;
          inside += in;
          nonzero += in && v[i] != 0.f;
          if (in) REQUIRE(v[i] == full[i]);
          else REQUIRE(v[i] == -7.f);
        }
    CHECK(inside == tore.channels() * std::max(0, std::min(r.x1, 37) - std::max(r.x0, 0)) *
                        std::max(0, std::min(r.y1, 23) - std::max(r.y0, 0)));
    if (inside > 100) CHECK(nonzero > 0);
  }
}

TEST_CASE("TORE read-out averaged over cells equals the read-out then each cell's mean, bit for bit, on every ISA", "[tore]") {
  yelan::test::IsaGuard guard;
  std::mt19937 rng(5);
  for (int k : {1, 3}) {
    ToreVolume tore(41, 25, ToreOptions{k, 200'000});
    for (int i = 0; i < 6000; ++i)
      tore.update(Event{std::int64_t(i) * 53, std::uint16_t(rng() % 41), std::uint16_t(rng() % 25), std::uint8_t(rng() % 2)});
    const std::int64_t T = 6000 * 53;
    const int C = tore.channels();
    for (auto isa : yelan::test::supported_isas()) {
      yelan::kernels::set_isa(isa);
      const auto full = read(tore, T);
      for (int d : {1, 2, 3}) {
        const int W = 41 / d, H = 25 / d, stride = 16;
        for (PixelRect r : {PixelRect{0, 0, W, H}, PixelRect{2, 1, W - 3, H - 2}, PixelRect{-5, -5, 3, 99}, PixelRect{4, 4, 4, 9}}) {
          INFO(yelan::kernels::isa_name(isa) << " k " << k << " d " << d << " rect " << r.x0 << "," << r.y0 << "," << r.x1 << "," << r.y1);
          std::vector<float> got(std::size_t(W) * H * stride, -3.f);
          tore.readout_mean(T, d, got.data(), W, stride, r);
          int written = 0;
          for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x)
              for (int c = 0; c < stride; ++c) {
                const float v = got[(std::size_t(y) * W + x) * stride + c];
                const bool in = c < C && x >= std::max(r.x0, 0) && x < r.x1 && y >= std::max(r.y0, 0) && y < r.y1;
                if (!in) {
                  REQUIRE(v == -3.f);
                  continue;
                }
                float sum = 0;
                for (int dy = 0; dy < d; ++dy)
                  for (int dx = 0; dx < d; ++dx) sum += at(full, tore, c, y * d + dy, x * d + dx);
                REQUIRE(v == sum * (1.f / float(d * d)));
                written += v != 0.f;
              }
          if (r.x0 == 0 && r.y0 == 0) CHECK(written > 0);
        }
      }
    }
  }
  std::vector<float> out(64);
  CHECK_THROWS_AS(ToreVolume(4, 4).readout_mean(0, 2, out.data(), 2, 5, PixelRect{0, 0, 2, 2}), std::invalid_argument);
}

TEST_CASE("TORE Baldwin read-out follows the original log scaling", "[tore]") {
  ToreVolume tore(3, 2);
  tore.update(Event{400, 1, 1, 1});
  tore.update(Event{1000, 1, 1, 1});
  tore.update(Event{1200, 0, 0, 0});
  std::vector<float> v(tore.volume_size());
  tore.readout_baldwin(1100, v.data());
  const float missing = float(std::log(5e6 + 1) - std::log(151.0));  // 10.4077
  auto px = [&](int c, int y, int x) { return v[(std::size_t(c) * 2 + y) * 3 + x]; };
  CHECK(px(0, 1, 1) == Approx(0.0).margin(1e-6));  // age 100 < min_t 150
  CHECK(px(1, 1, 1) == Approx(std::log(701.0) - std::log(151.0)).margin(3e-6));
  CHECK(px(2, 1, 1) == Approx(missing).margin(3e-6));
  CHECK(px(3, 0, 0) == Approx(missing).margin(3e-6));  // newer than T counts as missing
  CHECK(px(0, 0, 2) == Approx(missing).margin(3e-6));
  // ages beyond max_t clip to max_t
  tore.readout_baldwin(400 + 9'000'000, v.data(), BaldwinScale{150, 5'000'000});
  CHECK(px(1, 1, 1) == Approx(missing).margin(3e-6));
  CHECK_THROWS_AS(tore.readout_baldwin(0, v.data(), BaldwinScale{10, 5}), std::invalid_argument);
}

TEST_CASE("TORE batch update equals per-event update for every K, and ISAs agree", "[tore]") {
  yelan::test::IsaGuard guard;
  std::mt19937 rng(7);
  std::vector<Event> events;
  for (int i = 0; i < 5000; ++i)
    events.push_back(Event{i * 37, std::uint16_t(rng() % 19), std::uint16_t(rng() % 11),
                           std::uint8_t(rng() & 1)});
  events.push_back(Event{999999, 19, 0, 1});  // out of range: dropped, counted
  for (int k : {1, 2, 3, 4, 5, 8}) {
    INFO("k = " << k);
    ToreVolume one(19, 11, {k, 100'000}), batch(19, 11, {k, 100'000});
    for (const Event& e : events) one.update(e);
    batch.update(events);
    CHECK(one.out_of_range() == 1);
    CHECK(batch.out_of_range() == 1);
    std::vector<float> ref(one.volume_size()), got(one.volume_size());
    yelan::kernels::set_isa(yelan::kernels::Isa::scalar);
    one.readout(190'000, ref.data());
    std::vector<float> ref_b(ref.size()), got_b(ref.size());
    one.readout_baldwin(190'000, ref_b.data());
    for (auto isa : yelan::test::supported_isas()) {
      INFO(yelan::kernels::isa_name(isa));
      yelan::kernels::set_isa(isa);
      batch.readout(190'000, got.data(), 3);  // rows over 3 threads
      batch.readout_baldwin(190'000, got_b.data(), {}, 3);
      for (std::size_t i = 0; i < ref.size(); ++i) {
        REQUIRE(got[i] == Approx(ref[i]).margin(1e-6));
        REQUIRE(got_b[i] == Approx(ref_b[i]).margin(4e-6));
      }
    }
    // and the scalar path against the definition with std::log, for every slot
    int live = 0;
    for (int y = 0; y < 11; ++y)
      for (int x = 0; x < 19; ++x)
        for (int pol : {1, 0})
          for (int s = 0; s < k; ++s) {
            const std::int64_t t = one.slot(x, y, pol, s);
            double want = 0;
            if (t != ToreVolume::kEmpty && 190'000 - t < 100'000) {
              want = std::clamp(1 - std::log1p(double(190'000 - t)) / std::log(1e5), 0.0, 0.7) / 0.7;
              ++live;
            }
            const int c = (pol ? 0 : k) + s;
            REQUIRE(ref[(std::size_t(c) * 11 + y) * 19 + x] == Approx(want).margin(2e-6));
          }
    CHECK(live > 0);
  }
}

TEST_CASE("TORE reset empties every slot, and bad options throw", "[tore]") {
  ToreVolume tore(4, 4);
  tore.update(Event{10, 3, 3, 1});
  tore.update(Event{10, 4, 3, 1});
  CHECK(tore.out_of_range() == 1);
  tore.reset();
  CHECK(tore.out_of_range() == 0);
  CHECK(tore.slot(3, 3, 1, 0) == ToreVolume::kEmpty);
  for (float x : read(tore, 10)) REQUIRE(x == 0.f);
  CHECK_THROWS_AS(ToreVolume(0, 4), std::invalid_argument);
  CHECK_THROWS_AS(ToreVolume(4, -1), std::invalid_argument);
  CHECK_THROWS_AS(ToreVolume(4, 4, {0}), std::invalid_argument);
  CHECK_THROWS_AS(ToreVolume(4, 4, {65}), std::invalid_argument);
  CHECK_THROWS_AS(ToreVolume(4, 4, {3, 1}), std::invalid_argument);
  CHECK_THROWS_AS(ToreVolume(4, 4, {3, std::int64_t{1} << 31}), std::invalid_argument);
}

TEST_CASE("PixelRect::clipped keeps the part inside the frame", "[tore]") {
  const PixelRect in = PixelRect{-4, 3, 50, 17}.clipped(37, 23);
  CHECK((in.x0 == 0 && in.y0 == 3 && in.x1 == 37 && in.y1 == 17));
  CHECK((in.width() == 37 && in.height() == 14));
  CHECK(PixelRect{-9, -9, -2, 5}.clipped(37, 23).empty());
  CHECK(PixelRect{40, 0, 60, 5}.clipped(37, 23).empty());
  CHECK(PixelRect{}.empty());
}
