#include <catch2/catch.hpp>

#include <tuple>

#include "camera/usb/davis_device.h"
#include "camera/usb/fake_transport.h"
#include "camera/usb/protocol.h"
#include "usb_test_util.h"

using namespace yelan::camera::usb;
using yelan::camera::Event;
using yelan::test::usb::bytes;
using yelan::test::usb::col;
using yelan::test::usb::row;
using yelan::test::usb::ts;

namespace {

// A fake DAVIS346: chip 5 (DAVIS346B), 346 x 260, USB clock 80 MHz with no deviation.
FakeTransport fake_davis346() {
  FakeTransport t;
  t.set_config(module::sysinfo, sysinfo::logic_version, 18);
  t.set_config(module::sysinfo, sysinfo::chip_identifier, 5);
  t.set_config(module::dvs, dvs::size_columns, 346);
  t.set_config(module::dvs, dvs::size_rows, 260);
  t.set_config(module::sysinfo, sysinfo::usb_clock, 80);
  t.set_config(module::sysinfo, sysinfo::clock_deviation, 1000);
  return t;
}

using Write = std::tuple<int, int, std::uint32_t>;  // module, parameter, value

// The config writes among the recorded control transfers from index `from` on.
std::vector<Write> writes(const FakeTransport& t, std::size_t from = 0) {
  std::vector<Write> w;
  for (std::size_t i = from; i < t.controls().size(); ++i) {
    const ControlRecord& c = t.controls()[i];
    if (!c.out) continue;
    REQUIRE(c.request == 0xBF);
    REQUIRE(c.data.size() == 4);
    const std::uint32_t v = (std::uint32_t(c.data[0]) << 24) | (std::uint32_t(c.data[1]) << 16) |
                            (std::uint32_t(c.data[2]) << 8) | c.data[3];
    w.emplace_back(c.value, c.index, v);
  }
  return w;
}

struct Sleeps {
  std::vector<int> ms;
  DavisDevice::Sleep fn() {
    return [this](std::chrono::milliseconds d) { ms.push_back(static_cast<int>(d.count())); };
  }
};

}  // namespace

TEST_CASE("device: config words are vendor request 0xBF, value = module, index = parameter, big-endian", "[usb]") {
  FakeTransport t;
  DavisDevice d(t, [](auto) {});
  d.config_set(9, 1, 0x01020304);
  REQUIRE(t.controls().size() == 1);
  const ControlRecord& c = t.controls()[0];
  CHECK(c.out);
  CHECK(c.request == 0xBF);
  CHECK(c.value == 9);
  CHECK(c.index == 1);
  CHECK(c.data == std::vector<std::uint8_t>{1, 2, 3, 4});
  t.set_config(6, 1, 0xA1B2C3D4);
  CHECK(d.config_get(6, 1) == 0xA1B2C3D4u);
}

TEST_CASE("device: open reads SYSINFO and the DVS geometry", "[usb]") {
  FakeTransport t = fake_davis346();
  DavisDevice d(t, [](auto) {});
  const DavisInfo& info = d.open();
  CHECK(info.logic_version == 18);
  CHECK(info.chip_id == 5);
  CHECK(info.width == 346);
  CHECK(info.height == 260);
  CHECK_FALSE(info.invert_xy);
  CHECK(info.usb_clock_mhz == 80.0);
  for (const ControlRecord& c : t.controls()) {
    CHECK_FALSE(c.out);  // open only reads
    CHECK(c.request == 0xBF);
  }
}

TEST_CASE("device: open refuses chips other than the DAVIS346 and absurd sizes", "[usb]") {
  FakeTransport t = fake_davis346();
  t.set_config(module::sysinfo, sysinfo::chip_identifier, 2);  // DAVIS240C
  DavisDevice d(t, [](auto) {});
  CHECK_THROWS_WITH(d.open(), Catch::Contains("unsupported DAVIS chip identifier 2"));
  FakeTransport t2 = fake_davis346();
  t2.set_config(module::dvs, dvs::size_rows, 0);
  DavisDevice d2(t2, [](auto) {});
  CHECK_THROWS_AS(d2.open(), UsbError);
}

TEST_CASE("device: configure sends DAVIS346 biases, chip register and FPGA defaults, APS and IMU off", "[usb]") {
  FakeTransport t = fake_davis346();
  DavisDevice d(t, [](auto) {});
  d.open();
  const std::size_t before = t.controls().size();
  d.configure();
  const auto w = writes(t, before);
  REQUIRE(w.size() == 28 + 15 + 4 + 1);
  // Hand-packed bias words: VDAC(27,6) = 27 | 6<<6; N(5,255) = 0xF | 255<<4 | 5<<12;
  // P(2,58) = 0xD | 58<<4 | 2<<12; pad follower N(7,215) disabled = 0xE | 215<<4 | 7<<12;
  // shifted source (1,33) = 1<<4 | 33<<10.
  CHECK(w[0] == Write{5, 0, 411});
  CHECK(w[4] == Write{5, 4, 21 | 7 << 6});
  CHECK(w[6] == Write{5, 9, 0x7D7E});
  CHECK(w[8] == Write{5, 11, 0x5FFF});
  CHECK(w[11] == Write{5, 14, 0x23AD});
  CHECK(w[26] == Write{5, 35, 0x8410});
  CHECK(w[27] == Write{5, 36, 0x8410});
  CHECK(w[28] == Write{5, 128, 0});          // chip register starts at 128
  CHECK(w[41] == Write{5, 143, 1});          // on-chip gray counter
  CHECK(w[42] == Write{5, 144, 0});          // ADC reads pixels
  CHECK(w[43] == Write{0, 4, 1});            // drop external input on USB stall
  CHECK(w[44] == Write{0, 5, 1});            // drop DVS on USB stall
  CHECK(w[45] == Write{1, 4, 0});
  CHECK(w[46] == Write{1, 5, 0});
  CHECK(w[47] == Write{9, 1, 80000});        // 1 ms at 80 MHz
  for (const Write& x : w) {
    CHECK_FALSE((std::get<0>(x) == 2 && std::get<1>(x) == 4 && std::get<2>(x) != 0));  // APS run
    CHECK_FALSE((std::get<0>(x) == 3 && std::get<2>(x) != 0));                         // IMU
  }
}

TEST_CASE("device: start and stop send the acquisition sequence in order", "[usb]") {
  FakeTransport t = fake_davis346();
  Sleeps sleeps;
  DavisDevice d(t, sleeps.fn());
  d.open();
  d.configure();
  const std::size_t before = t.controls().size();
  d.start([](std::span<const Event>) {});
  CHECK(t.bulk_running());
  CHECK(t.clear_halt_calls() == 1);
  CHECK(sleeps.ms == std::vector<int>{10, 200, 50});
  const std::vector<Write> all_off = {{1, 3, 0}, {2, 4, 0}, {3, 2, 0}, {3, 3, 0}, {3, 4, 0},
                                      {4, 0, 0}, {0, 0, 0}, {0, 1, 0}, {9, 0, 0}, {0, 3, 0}};
  std::vector<Write> expected_start = all_off;
  for (Write w : std::vector<Write>{{0, 3, 1}, {9, 0, 1}, {0, 1, 1}, {0, 0, 1}, {1, 3, 1}}) expected_start.push_back(w);
  CHECK(writes(t, before) == expected_start);
  const std::size_t started = t.controls().size();
  d.stop();
  CHECK_FALSE(t.bulk_running());
  CHECK(writes(t, started) == all_off);
  d.stop();  // a second stop does nothing
  CHECK(writes(t, started).size() == all_off.size());
}

TEST_CASE("device: with APS and IMU asked for, start turns them on after DVS", "[usb]") {
  FakeTransport t = fake_davis346();
  DavisDevice d(t, [](auto) {});
  d.open();
  DavisConfig config;
  config.aps = config.imu = true;
  d.configure(config);
  const std::size_t before = t.controls().size();
  d.start({});
  const auto w = writes(t, before);
  REQUIRE(w.size() == 10 + 5 + 4);
  CHECK(std::vector<Write>(w.end() - 4, w.end()) == std::vector<Write>{{2, 4, 1}, {3, 2, 1}, {3, 3, 1}, {3, 4, 1}});
}

TEST_CASE("device: bulk buffers reach the sink as events, words split across buffers", "[usb]") {
  FakeTransport t = fake_davis346();
  DavisDevice d(t, [](auto) {});
  d.open();
  d.configure();
  auto stream = bytes({ts(5), row(3), col(7, true), ts(9), col(8, false)});
  t.queue_buffer({stream.begin(), stream.begin() + 5});  // ends mid-word
  t.queue_buffer({stream.begin() + 5, stream.end()});
  std::vector<Event> got;
  d.start([&](std::span<const Event> b) { got.insert(got.end(), b.begin(), b.end()); });
  for (int i = 0; i < 4; ++i) t.poll(std::chrono::milliseconds(0));
  REQUIRE(got.size() == 2);
  CHECK(got[0] == Event{5, 7, 3, 1});
  CHECK(got[1] == Event{9, 8, 3, 0});
  CHECK(d.state() == StreamState::streaming);
  CHECK(d.error().empty());
}

TEST_CASE("device: an unplug mid-stream keeps decoded events and reports the error", "[usb]") {
  FakeTransport t = fake_davis346();
  DavisDevice d(t, [](auto) {});
  d.open();
  d.configure();
  t.queue_buffer(bytes({ts(1), row(0), col(0, true), col(1, true)}));
  t.queue_buffer(bytes({ts(2), col(2, false)}));
  t.unplug_after_queue();
  std::vector<Event> got;
  d.start([&](std::span<const Event> b) { got.insert(got.end(), b.begin(), b.end()); });
  for (int i = 0; i < 5; ++i) REQUIRE_NOTHROW(t.poll(std::chrono::milliseconds(0)));
  CHECK(got.size() == 3);
  CHECK(got[2] == Event{2, 2, 0, 0});
  CHECK(d.state() == StreamState::disconnected);
  CHECK_THAT(d.error(), Catch::Contains("disconnected"));
  const std::size_t before = t.controls().size();
  REQUIRE_NOTHROW(d.stop());  // no control transfers to a device that is gone
  CHECK(t.controls().size() == before);
  CHECK(d.stats().events == 3);
}

TEST_CASE("device: control failures while stopping are reported, not thrown", "[usb]") {
  FakeTransport t = fake_davis346();
  DavisDevice d(t, [](auto) {});
  d.open();
  d.configure();
  d.start({});
  t.fail_controls();
  REQUIRE_NOTHROW(d.stop());
  CHECK_THAT(d.error(), Catch::Contains("stopping the device"));
  CHECK_FALSE(t.bulk_running());
}
