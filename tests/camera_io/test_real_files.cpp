// Every reader on the real recordings in ../shared/data/events, against the figures in its
// README.md (counts, ON counts, time spans, coordinate ranges, sensor sizes), plus the
// first and last five events decoded here (so a decoder change shows up as a failure).
#include <catch2/catch.hpp>

#include <algorithm>

#include "camera/io/event_reader.h"
#include "io_test_util.h"
#include "test_util.h"

using yelan::camera::Event;
using yelan::camera::open_event_file;

namespace {

struct Figures {
  std::string format;
  int width, height;
  std::uint64_t events, on;
  std::int64_t t_first, t_last;
  int x_max, y_max;
};

struct Seen {
  std::uint64_t events = 0, on = 0;
  std::int64_t t_first = 0, t_last = 0;
  int x_max = 0, y_max = 0;
  std::vector<Event> first, last;
  bool monotonic = true;
};

Seen scan(yelan::camera::EventReader& r) {
  Seen s;
  std::vector<Event> batch;
  while (true) {
    batch.clear();
    if (r.read(batch, 10007) == 0) break;  // an odd batch size on purpose
    for (const Event& e : batch) {
      if (s.events == 0) s.t_first = e.t;
      else if (e.t < s.t_last) s.monotonic = false;
      s.t_last = e.t;
      ++s.events;
      s.on += e.p;
      s.x_max = std::max<int>(s.x_max, e.x);
      s.y_max = std::max<int>(s.y_max, e.y);
      if (s.first.size() < 5) s.first.push_back(e);
      s.last.push_back(e);
      if (s.last.size() > 5) s.last.erase(s.last.begin());
    }
  }
  return s;
}

void check_figures(const std::string& rel, const Figures& want, const std::vector<Event>& first,
                   const std::vector<Event>& last) {
  const std::string path = yelan::test::shared_data_or_skip(rel);
  auto r = open_event_file(path);
  CHECK(r->info().format == want.format);
  CHECK(r->info().width == want.width);
  CHECK(r->info().height == want.height);
  Seen s = scan(*r);
  CHECK(s.events == want.events);
  CHECK(s.on == want.on);
  CHECK(s.t_first == want.t_first);
  CHECK(s.t_last == want.t_last);
  CHECK(s.x_max == want.x_max);
  CHECK(s.y_max == want.y_max);
  CHECK(s.monotonic);
  CHECK(r->warnings().total() == 0);
  CHECK(s.first == first);
  CHECK(s.last == last);
}

}  // namespace

TEST_CASE("AEDAT 4.0 DAVIS346 sample matches its README figures", "[io][aedat4][real]") {
  // README: 117,667 events (72,363 ON), x 0..345, y 0..259, t 1633953690975950..1633953691105949.
  check_figures("events/aestream_davis.aedat4",
                {"aedat4", 346, 260, 117667, 72363, 1633953690975950, 1633953691105949, 345, 259},
                {{1633953690975950, 218, 15, 1}, {1633953690975950, 306, 76, 1}, {1633953690975954, 178, 73, 0},
                 {1633953690975955, 89, 91, 0}, {1633953690975957, 57, 12, 1}},
                {{1633953691105940, 216, 19, 1}, {1633953691105943, 213, 16, 1}, {1633953691105944, 137, 25, 0},
                 {1633953691105944, 167, 114, 0}, {1633953691105949, 137, 56, 0}});
}

TEST_CASE("EVT 2.0 Gen3 sample matches its README figures", "[io][evt2][real]") {
  // README: 539,481 CD events (367,855 ON), x max 599, y max 475, t 1,317,888..1,367,888; 640x480.
  check_figures("events/evt2_sample.raw", {"evt2", 640, 480, 539481, 367855, 1317888, 1367888, 599, 475},
                {{1317888, 237, 121, 1}, {1317888, 246, 121, 1}, {1317888, 248, 132, 1}, {1317888, 239, 133, 1},
                 {1317888, 256, 134, 1}},
                {{1367887, 233, 108, 0}, {1367887, 242, 111, 0}, {1367887, 224, 143, 1}, {1367887, 240, 143, 1},
                 {1367888, 210, 142, 1}});
}

TEST_CASE("EVT 3.0 Gen4.1 sample matches its README counts and first timestamp", "[io][evt3][real]") {
  // README: 219,596 events (115,532 ON), x max 1279, y max 719, 1280x720, first t 11,718,656.
  // The README's last t (11,772,513) comes from expelliarmus, which counts every step back
  // of TIME_LOW as a wrap; the file's TIME_HIGH words only span 2861..2863 (x 4096 us), so
  // the last event cannot be later than 2863*4096+4095 = 11,730,943. We decode 11,727,457.
  check_figures("events/evt3_sample.raw", {"evt3", 1280, 720, 219596, 115532, 11718656, 11727457, 1279, 719},
                {{11718656, 874, 200, 0}, {11718656, 806, 200, 1}, {11718656, 882, 201, 0}, {11718656, 1085, 201, 1},
                 {11718656, 1235, 201, 1}},
                {{11727457, 1249, 573, 0}, {11727457, 549, 573, 1}, {11727457, 170, 572, 0}, {11727457, 1249, 572, 0},
                 {11727457, 1218, 572, 1}});
  CHECK(2863 * 4096 + 4095 >= 11727457);
}

TEST_CASE("time windows split a real stream exactly at t < T", "[io][window][real]") {
  const std::string path = yelan::test::shared_data_or_skip("events/evt2_sample.raw");
  auto r = open_event_file(path);
  std::uint64_t total = 0;
  std::int64_t t_end = 1317888 + 1000;
  std::vector<Event> w;
  while (true) {
    w.clear();
    while (r->read_until(w, t_end, 997) == 997) {
    }
    for (const Event& e : w) REQUIRE(e.t < t_end);
    auto next = r->peek_time();
    if (next) REQUIRE(*next >= t_end);
    total += w.size();
    if (!next) break;
    t_end += 1000;
  }
  CHECK(total == 539481);
  CHECK(t_end == 1317888 + 51000);  // 50 ms of data, windows of 1 ms, the last holds t = 1367888
}

TEST_CASE("seek positions a real stream on the first event at or after T", "[io][seek][real]") {
  const std::string path = yelan::test::shared_data_or_skip("events/aestream_davis.aedat4");
  auto r = open_event_file(path);
  CHECK(r->fast_seek());  // through the file's data table
  const auto all = yelan::test::read_all(*r);
  const std::int64_t T = 1633953691040000;
  const auto it = std::lower_bound(all.begin(), all.end(), T, [](const Event& e, std::int64_t t) { return e.t < t; });
  r->seek(T);
  std::vector<Event> rest = yelan::test::read_all(*r);
  REQUIRE(rest.size() == static_cast<std::size_t>(all.end() - it));
  CHECK(rest.front() == *it);
  r->rewind();
  CHECK(yelan::test::read_all(*r).size() == 117667);
  for (std::int64_t t : {std::int64_t{0}, all.front().t, all.back().t, all.back().t + 1}) {
    r->seek(t);
    const auto from = std::lower_bound(all.begin(), all.end(), t, [](const Event& e, std::int64_t v) { return e.t < v; });
    CHECK(yelan::test::read_all(*r).size() == static_cast<std::size_t>(all.end() - from));
  }
}

TEST_CASE("format detection by magic bytes, not by extension", "[io][detect][real]") {
  const std::string raw = yelan::test::shared_data_or_skip("events/evt3_sample.raw");
  const std::string aedat = yelan::test::shared_data_or_skip("events/aestream_davis.aedat4");
  yelan::test::ScratchDir dir("detect");
  const std::string a = dir.file("renamed.bin"), b = dir.file("renamed.txt");
  std::filesystem::copy_file(raw, a);
  std::filesystem::copy_file(aedat, b);
  CHECK(yelan::camera::detect_event_format(a) == "prophesee-raw");
  CHECK(yelan::camera::detect_event_format(b) == "aedat4");
  CHECK(open_event_file(a)->info().format == "evt3");
  CHECK(open_event_file(b)->info().format == "aedat4");
}
