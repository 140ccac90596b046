#include <catch2/catch.hpp>

#include <stdexcept>
#include <utility>
#include <vector>

#include "camera/repr/filters.h"

using namespace yelan::camera;

TEST_CASE("hot pixel filter drops a fixed list of pixels", "[filters]") {
  const std::vector<std::pair<int, int>> hot = {{1, 1}, {4, 0}};
  HotPixelFilter f(5, 3, hot);
  CHECK(f.hot_count() == 2);
  CHECK(f.is_hot(1, 1));
  CHECK_FALSE(f.is_hot(0, 1));
  CHECK_FALSE(f.is_hot(5, 0));
  CHECK_FALSE(f.is_hot(-1, 1));
  std::vector<Event> ev = {{0, 1, 1, 1}, {1, 0, 1, 0}, {2, 4, 0, 1}, {3, 1, 1, 0}, {4, 5, 0, 1}, {5, 2, 2, 1}};
  CHECK(f.apply(ev) == 2);
  REQUIRE(ev.size() == 2);
  CHECK(ev[0].t == 1);
  CHECK(ev[1].t == 5);
  CHECK(f.out_of_range() == 1);
  CHECK_THROWS_AS(f.add(5, 0), std::invalid_argument);
  CHECK_THROWS_AS(f.add(0, -1), std::invalid_argument);
}

TEST_CASE("hot pixels are learned as rates far above the median", "[filters]") {
  std::vector<Event> ev;
  for (int x = 0; x < 10; ++x)
    for (int i = 0; i < 2; ++i) ev.push_back({0, std::uint16_t(x), 0, 1});  // median 2
  for (int i = 0; i < 50; ++i) ev.push_back({0, 3, 2, 1});   // 50 > 10 x 2: hot
  for (int i = 0; i < 19; ++i) ev.push_back({0, 4, 2, 1});   // 19: under both bars
  for (int i = 0; i < 21; ++i) ev.push_back({0, 5, 2, 0});   // 21 > 20 and >= 20: hot
  auto f = HotPixelFilter::learn(ev, 10, 3);
  const std::vector<std::pair<int, int>> want = {{3, 2}, {5, 2}};
  CHECK(f.hot_pixels() == want);
  // a quiet recording: median 1, ratio 10 would flag 11 events, min_events keeps it clean
  std::vector<Event> quiet = {{0, 0, 0, 1}, {0, 1, 0, 1}};
  for (int i = 0; i < 11; ++i) quiet.push_back({0, 2, 0, 1});
  CHECK(HotPixelFilter::learn(quiet, 3, 1).hot_count() == 0);
  CHECK(HotPixelFilter::learn({}, 3, 1).hot_count() == 0);
}

TEST_CASE("background activity filter passes events with a recent neighbour", "[filters]") {
  BackgroundActivityFilter f(5, 5);  // 70 ms
  CHECK_FALSE(f.accept({0, 2, 2, 1}));        // nothing before it
  CHECK(f.accept({10'000, 3, 3, 0}));         // (2,2) 10 ms ago
  CHECK_FALSE(f.accept({20'000, 0, 0, 1}));   // corner, no neighbours
  CHECK_FALSE(f.accept({100'000, 2, 2, 1}));  // (3,3) 90 ms ago: too old
  CHECK_FALSE(f.accept({105'000, 2, 2, 1}));  // its own pixel does not count
  CHECK(f.accept({175'000, 3, 2, 1}));        // (2,2) exactly 70 ms ago
  CHECK_FALSE(f.accept({175'001, 4, 4, 1}));  // (3,3) last at 10 ms
  CHECK(f.accept({175'002, 4, 4, 1}) == false);
  CHECK(f.accept({175'003, 4, 3, 0}));        // (3,2) and (4,4) just now
  CHECK_FALSE(f.accept({1, 5, 0, 1}));        // outside
  CHECK(f.out_of_range() == 1);
  std::vector<Event> ev = {{0, 0, 0, 1}, {1, 1, 0, 1}, {2, 4, 4, 1}, {3, 0, 1, 0}};
  f.reset();
  CHECK(f.apply(ev) == 2);
  CHECK(ev[0].t == 1);
  CHECK(ev[1].t == 3);
}

TEST_CASE("refractory filter silences a pixel for a period after it fires", "[filters]") {
  RefractoryFilter f(3, 3, 1000);
  std::vector<Event> ev = {{0, 1, 1, 1},   {500, 1, 1, 0},  {600, 2, 1, 1}, {999, 1, 1, 1},
                           {1000, 1, 1, 1}, {1500, 1, 1, 0}, {2000, 1, 1, 0}, {2100, 3, 0, 1}};
  CHECK(f.apply(ev) == 4);
  std::vector<std::int64_t> t;
  for (const Event& e : ev) t.push_back(e.t);
  CHECK(t == std::vector<std::int64_t>{0, 600, 1000, 2000});
  CHECK(f.out_of_range() == 1);
  RefractoryFilter off(3, 3, 0);  // period 0: everything passes
  CHECK(off.accept({5, 0, 0, 1}));
  CHECK(off.accept({5, 0, 0, 1}));
  CHECK_THROWS_AS(RefractoryFilter(3, 3, -1), std::invalid_argument);
}
