#include <catch2/catch.hpp>

#include <tuple>

#include "camera/usb/dvxplorer_device.h"
#include "camera/usb/fake_transport.h"
#include "camera/usb/protocol.h"
#include "usb_test_util.h"

using namespace yelan::camera::usb;
using yelan::camera::Event;
using namespace yelan::test::usb;

namespace {

FakeTransport fake_dvxplorer(std::uint32_t chip = 20, std::uint32_t w = 640, std::uint32_t h = 480) {
  FakeTransport t;
  t.set_config(module::sysinfo, sysinfo::chip_identifier, chip);
  t.set_config(module::dvs, dvs::size_columns, w);
  t.set_config(module::dvs, dvs::size_rows, h);
  t.set_config(module::sysinfo, sysinfo::usb_clock, 80);
  t.set_config(module::sysinfo, sysinfo::clock_deviation, 1000);
  return t;
}

using Write = std::tuple<int, int, std::uint32_t>;  // module, parameter (register), value

std::vector<Write> writes(const FakeTransport& t, std::size_t from = 0) {
  std::vector<Write> w;
  for (std::size_t i = from; i < t.controls().size(); ++i) {
    const ControlRecord& c = t.controls()[i];
    if (!c.out) continue;
    REQUIRE(c.request == 0xBF);
    REQUIRE(c.data.size() == 4);
    w.emplace_back(c.value, c.index,
                   (std::uint32_t(c.data[0]) << 24) | (std::uint32_t(c.data[1]) << 16) | (std::uint32_t(c.data[2]) << 8) | c.data[3]);
  }
  return w;
}

std::uint32_t sensor_reg(const FakeTransport& t, std::uint16_t reg) { return t.config(5, reg); }

}  // namespace

TEST_CASE("dvxplorer device: open powers the sensor and loads its start-up registers", "[usb]") {
  FakeTransport t = fake_dvxplorer();
  std::vector<int> sleeps;
  DvxplorerDevice d(t, [&](std::chrono::milliseconds ms) { sleeps.push_back(static_cast<int>(ms.count())); });
  const DvxplorerInfo& info = d.open();
  CHECK(info.chip_id == 20);
  CHECK(info.width == 640);
  CHECK(info.height == 480);
  CHECK(sleeps == std::vector<int>{10});
  const auto w = writes(t);
  REQUIRE(w.size() == 1 + 6 + 6 + 4 + 3 + 3 + 1);
  CHECK(w[0] == Write{0, 3, 1});           // sensor out of reset first
  CHECK(w[1] == Write{5, 0x000D, 0x24});   // bias reset
  CHECK(w[7] == Write{5, 0x0018, 0x04});   // simple biases, "default" point
  CHECK(w[12] == Write{5, 0x001E, 0x08});
  CHECK(w[16] == Write{5, 0x3067, 0x80});  // MGROUP packet format
  CHECK(w.back() == Write{5, 0x3600, 0x01});
  for (std::size_t i = 1; i < w.size(); ++i) {
    CHECK(std::get<0>(w[i]) == 5);         // everything after power-up goes to the sensor
    CHECK(std::get<2>(w[i]) <= 0xFF);      // sensor registers are 8 bits
  }
}

TEST_CASE("dvxplorer device: open refuses unknown chips and absurd sizes", "[usb]") {
  FakeTransport t = fake_dvxplorer(5);
  DvxplorerDevice d(t, [](auto) {});
  CHECK_THROWS_WITH(d.open(), Catch::Contains("unsupported DVXplorer chip identifier 5"));
  FakeTransport t2 = fake_dvxplorer(20, 640, 5000);
  DvxplorerDevice d2(t2, [](auto) {});
  CHECK_THROWS_AS(d2.open(), UsbError);
}

TEST_CASE("dvxplorer device: configure leaves the sensor registers at the default readout", "[usb]") {
  FakeTransport t = fake_dvxplorer();
  DvxplorerDevice d(t, [](auto) {});
  d.open();
  d.configure();
  CHECK(t.config(0, 4) == 1);                    // drop external input on stall
  CHECK(t.config(0, 5) == 0);                    // keep DVS events
  CHECK(t.config(9, 1) == 80000);                // 1 ms at 80 MHz
  CHECK(sensor_reg(t, 0x3255) == 0x0D);          // 0x0C from open, global hold on, global reset off
  CHECK(sensor_reg(t, 0x3067) == 0x80);          // no flatten / ON-only / OFF-only
  CHECK(sensor_reg(t, 0x3200) == 0x06);          // subsampling and area blocking disabled
  CHECK(sensor_reg(t, 0x3204) == 0x00);          // no subsampling
  for (std::uint16_t r = 0x3205; r < 0x3205 + 40; r += 2) {
    CHECK(sensor_reg(t, r) == 0x7F);
    CHECK(sensor_reg(t, r + 1) == 0xFF);
  }
  CHECK(sensor_reg(t, 0x3242) == 0x02);
  CHECK(sensor_reg(t, 0x3258) == 0x01);
  CHECK(sensor_reg(t, 0x3262) == 15);
  CHECK(sensor_reg(t, 0x3251) == 10);
  CHECK(sensor_reg(t, 0x325D) == 0xBB);          // 48000 = 0xBB80
  CHECK(sensor_reg(t, 0x325E) == 0x80);
  CHECK(sensor_reg(t, 0x3300) == 0x01);          // cropper bypassed
  CHECK(sensor_reg(t, 0x3303) == 59);            // last row 479 is in group 59
  CHECK(sensor_reg(t, 0x3304) == 0xFF);
  CHECK(sensor_reg(t, 0x3307) == 0x02);          // last column 639 = 0x027F
  CHECK(sensor_reg(t, 0x3308) == 0x7F);
  CHECK(sensor_reg(t, 0x3500) == 0x01);          // activity filter bypassed
  CHECK(sensor_reg(t, 0x3502) == 44);            // 300 = 0x012C
  CHECK(std::get<1>(writes(t).back()) == 0x3201);  // digital block restarted last
  CHECK(std::get<2>(writes(t).back()) == 0x02);
}

TEST_CASE("dvxplorer device: the Lite (320x240) gets its own subsampling code and no binning", "[usb]") {
  FakeTransport t = fake_dvxplorer(19, 320, 240);
  DvxplorerDevice d(t, [](auto) {});
  d.open();
  d.configure();
  CHECK(sensor_reg(t, 0x3204) == 0x09);
  for (const Write& w : writes(t)) CHECK(std::get<1>(w) != 0x3202);
  CHECK(sensor_reg(t, 0x3303) == 29);            // last row 239
  CHECK(sensor_reg(t, 0x3308) == 0x3F);          // last column 319 = 0x013F
}

TEST_CASE("dvxplorer device: start, stop and close send the acquisition sequence in order", "[usb]") {
  FakeTransport t = fake_dvxplorer();
  std::size_t started = 0, stopped = 0;
  const std::vector<Write> all_off = {{1, 3, 0}, {3, 2, 0}, {3, 3, 0}, {3, 4, 0},
                                      {4, 0, 0}, {0, 0, 0}, {0, 1, 0}, {9, 0, 0}};
  {
    std::vector<int> sleeps;
    DvxplorerDevice d(t, [&](std::chrono::milliseconds ms) { sleeps.push_back(static_cast<int>(ms.count())); });
    d.open();
    d.configure();
    const std::size_t before = t.controls().size();
    sleeps.clear();
    d.start({});
    CHECK(t.bulk_running());
    CHECK(t.clear_halt_calls() == 1);
    CHECK(sleeps == std::vector<int>{10, 50});
    std::vector<Write> expected = all_off;
    for (Write w : std::vector<Write>{{9, 0, 1}, {0, 1, 1}, {0, 0, 1}, {1, 3, 1},
                                      {5, 0x3238, 1}, {5, 0x3238, 0}, {5, 0x3000, 2}})
      expected.push_back(w);
    CHECK(writes(t, before) == expected);
    started = t.controls().size();
    d.stop();
    CHECK_FALSE(t.bulk_running());
    std::vector<Write> expected_stop = {{5, 0x3000, 0}};
    expected_stop.insert(expected_stop.end(), all_off.begin(), all_off.end());
    CHECK(writes(t, started) == expected_stop);
    stopped = t.controls().size();
  }
  CHECK(writes(t, stopped) == std::vector<Write>{{0, 3, 0}});  // closing puts the sensor in reset
}

TEST_CASE("dvxplorer device: bulk data becomes events, an unplug keeps them and is reported", "[usb]") {
  FakeTransport t = fake_dvxplorer();
  DvxplorerDevice d(t, [](auto) {});
  d.open();
  d.configure();
  auto stream = bytes({ts(3), dvx_col(10), dvx_groups(1, 0, false), dvx_pixels(true, 0b11, true), ts(4),
                       dvx_col(639), dvx_groups(59, 0, false), dvx_pixels(false, 0x80, false)});
  t.queue_buffer({stream.begin(), stream.begin() + 7});  // cut mid-word
  t.queue_buffer({stream.begin() + 7, stream.end()});
  t.unplug_after_queue();
  std::vector<Event> got;
  d.start([&](std::span<const Event> b) { got.insert(got.end(), b.begin(), b.end()); });
  for (int i = 0; i < 4; ++i) REQUIRE_NOTHROW(t.poll(std::chrono::milliseconds(0)));
  REQUIRE(got.size() == 3);
  CHECK(got[0] == Event{3, 10, 8, 1});
  CHECK(got[1] == Event{3, 10, 9, 1});
  CHECK(got[2] == Event{4, 639, 479, 0});
  CHECK_THAT(d.error(), Catch::Contains("disconnected"));
  const std::size_t before = t.controls().size();
  REQUIRE_NOTHROW(d.stop());
  CHECK(t.controls().size() == before);
}
