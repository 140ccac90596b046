#include <catch2/catch.hpp>

#include <cmath>
#include <stdexcept>
#include <vector>

#include "camera/repr/frames.h"
#include "camera/repr/time_surface.h"

using namespace yelan::camera;

namespace {
std::vector<Event> repeat(int n, Event e) { return std::vector<Event>(std::size_t(n), e); }
void append(std::vector<Event>& to, const std::vector<Event>& more) { to.insert(to.end(), more.begin(), more.end()); }
}  // namespace

TEST_CASE("count frame: DHP19 3-sigma normalisation of hand-made counts", "[frames]") {
  // counts {1, 2, 3, 6} on a 4x3 sensor: mean 3, population variance 3.5, 3 sigma = 5.6125
  std::vector<Event> ev;
  append(ev, repeat(1, {0, 0, 0, 1}));
  append(ev, repeat(2, {0, 1, 0, 0}));
  append(ev, repeat(3, {0, 2, 1, 1}));
  append(ev, repeat(6, {0, 3, 2, 0}));
  ev.push_back({0, 4, 0, 1});  // outside: skipped and counted
  std::vector<float> f(12, -1.f);
  CHECK(count_frame(ev, 4, 3, f.data()) == 1);
  const double three_sigma = 3 * std::sqrt(3.5);
  CHECK(f[0] == Approx(1 / three_sigma).margin(1e-6));  // 0.17817
  CHECK(f[1] == Approx(2 / three_sigma).margin(1e-6));
  CHECK(f[1 * 4 + 2] == Approx(3 / three_sigma).margin(1e-6));
  CHECK(f[2 * 4 + 3] == 1.f);  // 6 / 5.61 > 1: clipped
  CHECK(f[5] == 0.f);
  int zeros = 0;
  for (float v : f) zeros += v == 0.f;
  CHECK(zeros == 8);
}

TEST_CASE("count frame: equal counts saturate (sigma floor), an empty window stays zero", "[frames]") {
  std::vector<Event> ev = {{0, 0, 0, 1}, {0, 2, 1, 0}, {5, 1, 2, 1}};
  std::vector<float> f(9);
  count_frame(ev, 3, 3, f.data());
  CHECK(f[0] == 1.f);
  CHECK(f[1 * 3 + 2] == 1.f);
  CHECK(f[2 * 3 + 1] == 1.f);
  CHECK(f[4] == 0.f);
  count_frame({}, 3, 3, f.data());
  for (float v : f) CHECK(v == 0.f);
}

TEST_CASE("voxel grid splits each polarity linearly between the two nearest bins", "[frames]") {
  // 3 bins over [0, 100] us: u = 2 (t / 100)
  std::vector<Event> ev = {
      {25, 1, 0, 1},   // u = 0.5: +0.5 to bins 0 and 1
      {100, 1, 0, 0},  // u = 2: -1 to bin 2
      {80, 0, 1, 1},   // u = 1.6: +0.4 to bin 1, +0.6 to bin 2
      {0, 0, 0, 1},    // u = 0: +1 to bin 0
      {-50, 0, 0, 0},  // before the window: clamped to bin 0
      {10, 2, 1, 1},   // x out of range (width 2): skipped
  };
  std::vector<float> v(3 * 2 * 2, 9.f);
  CHECK(voxel_grid(ev, 2, 2, 3, 0, 100, v.data()) == 1);
  auto at = [&](int b, int y, int x) { return v[(std::size_t(b) * 2 + y) * 2 + x]; };
  CHECK(at(0, 0, 1) == Approx(0.5));
  CHECK(at(1, 0, 1) == Approx(0.5));
  CHECK(at(2, 0, 1) == Approx(-1.0));
  CHECK(at(1, 1, 0) == Approx(0.4));
  CHECK(at(2, 1, 0) == Approx(0.6));
  CHECK(at(0, 0, 0) == Approx(0.0));  // +1 and -1
  CHECK(at(0, 1, 1) == 0.f);
  double total = 0;
  for (float x : v) total += x;
  CHECK(total == Approx(0.5 + 0.5 - 1 + 1.0 + 1 - 1));
  // one bin, zero-length window
  std::vector<float> one(4);
  voxel_grid(ev, 2, 2, 1, 7, 7, one.data());
  CHECK(one[1] == Approx(0.0));  // +1 (t=25) and -1 (t=100) at (1, 0)
  CHECK(one[2] == Approx(1.0));
  CHECK_THROWS_AS(voxel_grid(ev, 2, 2, 0, 0, 100, one.data()), std::invalid_argument);
  CHECK_THROWS_AS(voxel_grid(ev, 2, 2, 3, 100, 0, one.data()), std::invalid_argument);
}

TEST_CASE("time surface decays exponentially per pixel and polarity", "[frames]") {
  TimeSurface ts(3, 2, 1000);
  ts.update(Event{0, 1, 0, 1});
  ts.update(Event{500, 1, 0, 0});
  ts.update(Event{200, 2, 1, 1});
  ts.update(Event{300, 2, 1, 1});  // replaces 200
  ts.update(Event{2000, 0, 1, 0});  // newer than the read-out: reads 0
  ts.update(Event{1, 3, 0, 1});     // outside
  CHECK(ts.out_of_range() == 1);
  std::vector<float> v(ts.volume_size(), -1.f);
  ts.readout(1000, v.data());
  auto at = [&](int c, int y, int x) { return v[(std::size_t(c) * 2 + y) * 3 + x]; };
  CHECK(at(0, 0, 1) == Approx(std::exp(-1.0)).margin(1e-7));
  CHECK(at(1, 0, 1) == Approx(std::exp(-0.5)).margin(1e-7));
  CHECK(at(0, 1, 2) == Approx(std::exp(-0.7)).margin(1e-7));
  CHECK(at(1, 1, 0) == 0.f);
  CHECK(at(0, 0, 0) == 0.f);
  ts.readout(2000, v.data());
  CHECK(at(1, 1, 0) == 1.f);
  ts.reset();
  ts.readout(2000, v.data());
  for (float x : v) CHECK(x == 0.f);
  CHECK_THROWS_AS(TimeSurface(3, 2, 0), std::invalid_argument);
}

TEST_CASE("event window keeps the last span of time or the last N events", "[frames]") {
  auto by_time = EventWindow::by_time(20);
  for (std::int64_t t : {0, 5, 10, 20, 29, 30}) by_time.push({t, 0, 0, 1});
  by_time.drop_before(30);  // keeps t in (10, 30]
  auto kept = by_time.events();
  REQUIRE(kept.size() == 3);
  CHECK(kept[0].t == 20);
  CHECK(kept[2].t == 30);
  auto by_count = EventWindow::by_count(2);
  for (std::int64_t t : {1, 2, 3}) by_count.push({t, 0, 0, 1});
  by_count.drop_before(1000);
  REQUIRE(by_count.events().size() == 2);
  CHECK(by_count.events()[0].t == 2);
  CHECK_THROWS_AS(EventWindow::by_count(0), std::invalid_argument);
  CHECK_THROWS_AS(EventWindow::by_time(0), std::invalid_argument);
}
