#include <catch2/catch.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "camera/io/event_reader.h"
#include "camera/io/event_writer.h"
#include "camera/usb/davis_device.h"
#include "camera/usb/fake_transport.h"
#include "camera/usb/libusb_transport.h"
#include "camera/usb/protocol.h"
#include "camera/usb/recorder.h"
#include "engine/cli/cli.h"
#include "fake_camera.h"
#include "usb_test_util.h"
#include "cli_util.h"

using namespace yelan::camera::usb;
using yelan::camera::Event;
using yelan::camera::usb::DavisDecoder;
using yelan::test::usb::bytes;
using yelan::test::usb::fake_davis346;
using yelan::test::usb::col;
using yelan::test::usb::row;
using yelan::test::usb::ts;
using yelan::test::usb::wrap;

namespace {


struct CollectingWriter : yelan::camera::EventWriter {
  std::vector<Event> events;
  int closes = 0;
  void write(std::span<const Event> e) override { events.insert(events.end(), e.begin(), e.end()); }
  void close() override { ++closes; }
};

using yelan::test::usb::camera_attached;

using yelan::test::CliResult;
CliResult cli(std::vector<std::string> argv) { return yelan::test::run_cli(std::move(argv)); }

}  // namespace

TEST_CASE("record: every decoded event reaches the writer, which is closed when the stream ends", "[usb]") {
  FakeTransport t = fake_davis346();
  DavisDevice d(t, [](auto) {});
  d.open();
  d.configure();
  t.queue_buffer(bytes({ts(10), row(4), col(1, true)}));
  t.queue_buffer(bytes({wrap(1), col(2, false), row(259), col(345, true)}));
  t.unplug_after_queue();
  CollectingWriter w;
  int polls = 0;
  RecordResult r = record(d, t, w, [&] { return ++polls < 100; });
  CHECK(polls < 10);  // ended by the unplug, not by keep_going
  CHECK(w.closes == 1);
  REQUIRE(w.events.size() == 3);
  CHECK(w.events[0] == Event{10, 1, 4, 1});
  CHECK(w.events[2] == Event{32768, 345, 259, 1});
  CHECK(r.events == 3);
  CHECK(r.t_first == 10);
  CHECK(r.t_last == 32768);
  CHECK_THAT(r.error, Catch::Contains("disconnected"));
  CHECK(r.stats.events == 3);
}

TEST_CASE("record: stopping on request (Ctrl-C) stops the device and finishes the text file", "[usb]") {
  FakeTransport t = fake_davis346();
  DavisDevice d(t, [](auto) {});
  d.open();
  d.configure();
  for (int i = 0; i < 10; ++i) t.queue_buffer(bytes({ts(static_cast<std::uint16_t>(100 * i + 1)), row(2), col(static_cast<std::uint16_t>(i), i % 2)}));
  const auto dir = std::filesystem::temp_directory_path() / ("yelan_usb_rec_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "rec.txt").string();
  yelan::camera::StreamInfo info;
  info.width = 346;
  info.height = 260;
  auto writer = yelan::camera::open_event_writer(path, info);
  int polls = 0;
  RecordResult r = record(d, t, *writer, [&] { return polls++ < 4; });  // "Ctrl-C" after 4 polls
  CHECK(r.error.empty());
  CHECK(r.events == 4);
  CHECK_FALSE(t.bulk_running());
  std::ifstream in(path);
  REQUIRE(in.good());
  std::vector<std::string> data;
  for (std::string line; std::getline(in, line);)
    if (!line.empty() && line[0] != '#') data.push_back(line);
  CHECK(data == std::vector<std::string>{"1 0 2 0", "101 1 2 1", "201 2 2 0", "301 3 2 1"});
  int leftovers = 0;
  for (const auto& e : std::filesystem::directory_iterator(dir)) leftovers += e.path().filename() != "rec.txt";
  CHECK(leftovers == 0);  // no temporary file left beside it
  std::filesystem::remove_all(dir);
}

TEST_CASE("enumeration with libusb works and finds no camera on a machine without one", "[usb]") {
  std::vector<DeviceInfo> found;
  REQUIRE_NOTHROW(found = list_devices());
  for (const DeviceInfo& d : found) {
    CHECK(d.vendor_id == 0x152A);
    CHECK((d.product_id == 0x841A || d.product_id == 0x8419));
  }
  if (!camera_attached()) CHECK(found.empty());
}

TEST_CASE("opening a camera that is not attached is a UsbError naming it", "[usb]") {
  DeviceInfo gone;
  gone.model = Model::davis346;
  gone.bus = 250;
  gone.address = 127;
  CHECK_THROWS_WITH(LibusbTransport(gone), Catch::Contains("DAVIS346 at bus 250 address 127"));
}

TEST_CASE("yelan devices without a camera says so and exits 0", "[usb]") {
  if (camera_attached()) return;
  CliResult r = cli({"devices"});
  CHECK(r.code == 0);
  CHECK_THAT(r.out, Catch::Contains("no camera found"));
  CHECK(cli({"devices", "extra"}).code == 2);
}

TEST_CASE("yelan record without a camera exits 1 with a clear message and writes nothing", "[usb]") {
  if (camera_attached()) return;
  const auto path = std::filesystem::temp_directory_path() / ("yelan_usb_none_" + std::to_string(::getpid()) + ".txt");
  CliResult r = cli({"record", "--duration", "1s", path.string()});
  CHECK(r.code == 1);
  CHECK_THAT(r.err, Catch::Contains("no camera found"));
  CHECK_FALSE(std::filesystem::exists(path));
}

TEST_CASE("yelan record rejects bad durations and unknown output formats with exit 2", "[usb]") {
  for (const char* bad : {"0s", "-1s", "ten", "10parsecs", "", "5x"}) {
    INFO(bad);
    CliResult r = cli({"record", "--duration", bad, "out.txt"});
    CHECK(r.code == 2);
    CHECK_THAT(r.err, Catch::Contains("--duration expects"));
  }
  CliResult r = cli({"record", "--duration", "1s", "out.mp4"});
  CHECK(r.code == 2);
  CHECK_THAT(r.err, Catch::Contains("output format"));
  CHECK(cli({"record"}).code == 2);
  CHECK(cli({"record", "a.txt", "b.txt"}).code == 2);
}

TEST_CASE("record: .txt, .aedat4 and .yelan.h5 recordings read back as the decoded events", "[usb]") {
  // A stream with every DAVIS word kind, cut into USB buffers of odd sizes.
  std::mt19937 rng(5);
  std::vector<std::uint16_t> words = {ts(0), row(0)};
  std::uint16_t t = 0;
  for (int i = 0; i < 20000; ++i) {
    const unsigned k = rng() % 10;
    if (k == 0) {
      t = static_cast<std::uint16_t>(std::min<int>(0x7FFF, t + 1 + rng() % 40));
      words.push_back(ts(t));
    } else if (k == 1 && rng() % 20 == 0) {
      words.push_back(wrap(1));
      t = 0;
    } else if (k == 2) {
      words.push_back(row(static_cast<std::uint16_t>(rng() % 260)));
    } else if (k == 3) {
      words.push_back(yelan::test::usb::code(5, static_cast<std::uint16_t>(rng() % 256)));  // IMU byte
    } else {
      words.push_back(col(static_cast<std::uint16_t>(rng() % 346), rng() % 2));
    }
  }
  const std::vector<std::uint8_t> stream = bytes(words);
  std::vector<Event> expected;
  DavisDecoder reference;
  reference.feed(stream, expected);
  REQUIRE(expected.size() > 10000);

  const auto dir = std::filesystem::temp_directory_path() / ("yelan_usb_fmt_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  for (const char* name : {"rec.txt", "rec.aedat4", "rec.yelan.h5"}) {
    INFO(name);
    FakeTransport t = fake_davis346();
    DavisDevice d(t, [](auto) {});
    d.open();
    d.configure();
    for (std::size_t at = 0; at < stream.size();) {
      const std::size_t n = std::min<std::size_t>(stream.size() - at, 1 + rng() % 9000);
      t.queue_buffer({stream.begin() + static_cast<std::ptrdiff_t>(at), stream.begin() + static_cast<std::ptrdiff_t>(at + n)});
      at += n;
    }
    t.unplug_after_queue();
    const std::string path = (dir / name).string();
    yelan::camera::StreamInfo info;
    info.width = 346;
    info.height = 260;
    auto writer = yelan::camera::open_event_writer(path, info);
    RecordResult r = record(d, t, *writer, [] { return true; });
    REQUIRE(r.events == expected.size());
    auto reader = yelan::camera::open_event_file(path);
    std::vector<Event> back;
    while (reader->read(back, 1 << 16) > 0) {
    }
    CHECK(reader->info().width == 346);
    CHECK(reader->info().height == 260);
    CHECK(reader->warnings().total() == 0);
    REQUIRE(back.size() == expected.size());
    CHECK(back == expected);
  }
  std::filesystem::remove_all(dir);
}
