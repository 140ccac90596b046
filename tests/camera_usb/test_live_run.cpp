// `yelan run --camera` without hardware: a scripted DAVIS346 (FakeTransport) streams into
// the pose pipeline through cli::run_live, then is unplugged or stopped by SIGINT; the
// poses must equal those of the same events pushed straight into a PosePipeline.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>

#include "camera/io/h5.h"
#include "camera/usb/davis_decoder.h"
#include "camera/usb/davis_device.h"
#include "camera/usb/fake_transport.h"
#include "camera/usb/protocol.h"
#include "cli_util.h"
#include "engine/cli/camera_open.h"
#include "engine/cli/run_live.h"
#include "engine/run/pipeline.h"
#include "fake_camera.h"
#include "usb_test_util.h"

using namespace yelan::camera::usb;
using yelan::camera::Event;
using yelan::test::contains;
using yelan::test::run_cli;
using yelan::test::slurp;
using yelan::test::usb::bytes;
using yelan::test::usb::fake_davis346;
using yelan::test::usb::col;
using yelan::test::usb::row;
using yelan::test::usb::ts;
using yelan::test::usb::wrap;

namespace {


// USB buffers of 32.768 ms each (one timestamp wrap apart), 301 events each at odd places.
std::vector<std::vector<std::uint8_t>> buffers(int n) {
  std::mt19937 rng(11);
  std::vector<std::vector<std::uint8_t>> out;
  for (int b = 0; b < n; ++b) {
    std::vector<std::uint16_t> w;
    if (b > 0) w.push_back(wrap(1));
    for (int i = 0; i < 301; ++i) {
      w.push_back(ts(static_cast<std::uint16_t>(i * 100 + 7)));
      w.push_back(row(static_cast<std::uint16_t>(60 + rng() % 140)));
      w.push_back(col(static_cast<std::uint16_t>(100 + rng() % 150), rng() % 2));
    }
    out.push_back(bytes(w));
  }
  return out;
}

// The CSV rows PosePipeline gives for the first `n` buffers, decoded and pushed as the device does.
struct Expected {
  std::vector<std::string> rows;
  std::uint64_t events = 0;
  std::int64_t last_t = 0;
};
Expected expected_rows(const std::string& weights, const std::vector<std::vector<std::uint8_t>>& bufs, std::size_t n) {
  yelan::run::PosePipeline pipe(weights, 346, 260, {});
  DavisDecoder dec;
  Expected e;
  auto keep = [&](const yelan::run::Pose& p) { e.rows.push_back(yelan::run::pose_csv_row(p)); };
  for (std::size_t b = 0; b < n; ++b) {
    std::vector<Event> ev;
    dec.feed(bufs[b], ev);
    e.events += ev.size();
    e.last_t = ev.back().t;
    pipe.push(ev, keep);
  }
  pipe.finish(e.last_t, keep);
  return e;
}

std::vector<std::string> data_lines(const std::string& text) {
  std::vector<std::string> rows;
  std::istringstream in(text);
  std::string line;
  std::getline(in, line);  // header
  while (std::getline(in, line)) rows.push_back(line);
  return rows;
}

struct Live {
  FakeTransport t = fake_davis346();
  DavisDevice d{t, [](auto) {}};
  Live() {
    d.open();
    d.configure();
  }
};

using yelan::test::usb::camera_attached;

}  // namespace

TEST_CASE("live run: a camera unplugged mid-run keeps every pose, names the failure and exits 1", "[usb][run]") {
  yelan::test::CliTempDir dir("live-unplug");
  REQUIRE(run_cli({"weights", "init", "--config", "micro", "--seed", "3", "-o", dir / "w.h5"}).code == 0);
  const auto bufs = buffers(9);  // 9 x 32.768 ms: about 14 ticks at 50 Hz
  const Expected want = expected_rows(dir / "w.h5", bufs, bufs.size());
  REQUIRE(want.events == 9 * 301);
  REQUIRE(want.rows.size() >= 10);
  for (const char* name : {"p.csv", "p.json", "p.h5"}) {
    INFO(name);
    Live cam;
    for (const auto& b : bufs) cam.t.queue_buffer(b);
    cam.t.unplug_after_queue();
    yelan::cli::LiveRun live;
    live.setup.weights = dir / "w.h5";
    live.setup.out = dir / name;
    live.camera_name = "fake DAVIS346";
    live.progress = std::string(name) == "p.csv";  // as on a terminal
    int asked = 0;
    std::ostringstream out, err;
    const int code = yelan::cli::run_live(cam.d, cam.t, live, [&] { return ++asked < 1000; }, out, err);
    CHECK(code == 1);
    CHECK(asked < 20);  // ended by the unplug, not by keep_going
    CHECK_FALSE(cam.t.bulk_running());
    const std::string e = err.str();
    char at[32];
    std::snprintf(at, sizeof at, "%.3f s", double(want.last_t) * 1e-6);
    CHECK(contains(e, "the camera stopped sending after 2709 events at t=" + std::string(at) + ": "));
    CHECK(contains(e, "device disconnected (LIBUSB_TRANSFER_NO_DEVICE)"));
    if (live.progress) {
      CHECK(e.rfind("\r0 poses, 0.0 poses/s, stage 1 on 0% of ticks, 0 events", 0) == 0);
      CHECK(contains(e, "events   \n"));  // the status line ends before the messages
    } else {
      CHECK_FALSE(contains(e, "\r"));
    }
    CHECK(contains(e, "the " + std::to_string(want.rows.size()) + " poses computed are written to " + (dir / name)));
    CHECK(contains(out.str(), "fake DAVIS346: 2709 events, " + std::to_string(want.rows.size()) + " poses"));
    if (std::string(name) == "p.csv") {
      CHECK(data_lines(slurp(dir / name)) == want.rows);
    } else if (std::string(name) == "p.json") {
      const std::string json = slurp(dir / name);
      std::size_t n = 0;
      for (auto at = json.find("\"t_us\""); at != std::string::npos; at = json.find("\"t_us\"", at + 1)) ++n;
      CHECK(n == want.rows.size());
    } else {
      namespace h5 = yelan::camera::h5;
      const h5::H5Id f = h5::open_file(dir / name);
      const h5::H5Id ds = h5::check(H5Dopen2(f.get(), "t_us", H5P_DEFAULT), "t_us");
      REQUIRE(h5::shape(ds.get()) == std::vector<hsize_t>{want.rows.size()});
      std::vector<std::int64_t> t(want.rows.size());
      h5::read_rows(ds.get(), H5T_NATIVE_INT64, 0, t.size(), t.data());
      for (std::size_t i = 0; i < t.size(); ++i) CHECK(std::to_string(t[i]) == want.rows[i].substr(0, want.rows[i].find(',')));
    }
  }
}

TEST_CASE("live run: SIGINT or SIGTERM stops it with exit 0, and the CSV holds each pose as soon as it is computed", "[usb][run]") {
  yelan::test::CliTempDir dir("live-sigint");
  REQUIRE(run_cli({"weights", "init", "--config", "micro", "--seed", "3", "-o", dir / "w.h5"}).code == 0);
  const auto bufs = buffers(12);
  const Expected want = expected_rows(dir / "w.h5", bufs, 7);  // stopped after 7 buffers
  REQUIRE(!want.rows.empty());
  for (int sig : {SIGINT, SIGTERM}) {
    INFO(sig);
    Live cam;
    for (const auto& b : bufs) cam.t.queue_buffer(b);
    yelan::cli::LiveRun live;
    live.setup.weights = dir / "w.h5";
    live.setup.out = dir / ("p" + std::to_string(sig) + ".csv");
    live.camera_name = "fake DAVIS346";
    std::vector<std::string> rows_when_interrupted;
    int asked = 0;
    std::ostringstream out, err;
    int code = -1;
    {
      yelan::cli::InterruptGuard guard;
      auto until = yelan::cli::until_stopped(std::nullopt);
      code = yelan::cli::run_live(cam.d, cam.t, live, [&] {
        if (++asked == 8) {
          rows_when_interrupted = data_lines(slurp(*live.setup.out));
          std::raise(sig);  // what Ctrl-C or kill does; the guard turns it into a flag
        }
        return until();
      }, out, err);
      CHECK(yelan::cli::InterruptGuard::interrupted());
    }
    INFO(err.str());
    CHECK(code == 0);
    CHECK(asked == 8);
    CHECK(cam.t.pending_buffers() == 5);  // the 7 polled buffers were all the pipeline saw
    CHECK_FALSE(cam.t.bulk_running());
    CHECK_FALSE(contains(err.str(), "stopped sending"));
    const auto rows = data_lines(slurp(*live.setup.out));
    CHECK(rows == want.rows);
    // Rows were on disk before the run ended; the end adds only the ticks up to the last event.
    REQUIRE(!rows_when_interrupted.empty());
    REQUIRE(rows_when_interrupted.size() <= rows.size());
    CHECK(std::equal(rows_when_interrupted.begin(), rows_when_interrupted.end(), rows.begin()));
  }
}

TEST_CASE("live run: a link planted at --out is refused, not written through (the live CSV grows in place)", "[usb][run]") {
  yelan::test::CliTempDir dir("live-link");
  REQUIRE(run_cli({"weights", "init", "--config", "micro", "--seed", "3", "-o", dir / "w.h5"}).code == 0);
  const std::string victim = dir / "victim";
  { std::ofstream(victim) << "precious"; }
  REQUIRE(::symlink(victim.c_str(), (dir / "p.csv").c_str()) == 0);
  Live cam;
  for (const auto& b : buffers(2)) cam.t.queue_buffer(b);
  yelan::cli::LiveRun live;
  live.setup.weights = dir / "w.h5";
  live.setup.out = dir / "p.csv";
  live.camera_name = "fake DAVIS346";
  std::ostringstream out, err;
  CHECK_THROWS_WITH(yelan::cli::run_live(cam.d, cam.t, live, [] { return true; }, out, err),
                    Catch::Contains("is a symbolic link: refusing to write through it"));
  CHECK(slurp(victim) == "precious");
}

TEST_CASE("yelan run --camera without a camera exits 1 with a clear message; --camera with a FILE is a usage error", "[usb][run]") {
  yelan::test::CliTempDir dir("live-none");
  REQUIRE(run_cli({"weights", "init", "--config", "micro", "--seed", "3", "-o", dir / "w.h5"}).code == 0);
  if (!camera_attached()) {
    for (std::vector<std::string> args : {std::vector<std::string>{"--camera"}, {"--camera", "00000499"},
                                         {"--camera=00000499", "--duration", "1s"}}) {
      std::vector<std::string> argv = {"run", "--weights", dir / "w.h5", "--out", dir / "p.csv"};
      argv.insert(argv.end(), args.begin(), args.end());
      const auto r = run_cli(argv);
      INFO(r.err);
      CHECK(r.code == 1);
      CHECK(contains(r.err, "no camera found"));
      CHECK_FALSE(std::filesystem::exists(dir / "p.csv"));
    }
  }
  std::ofstream(dir / "rec.txt") << "# empty\n";
  for (std::vector<std::string> args : {std::vector<std::string>{"--camera", dir / "rec.txt"},
                                       {dir / "rec.txt", "--camera"}, {"--camera=0001", dir / "rec.txt"}}) {
    std::vector<std::string> argv = {"run", "--weights", dir / "w.h5"};
    argv.insert(argv.end(), args.begin(), args.end());
    const auto r = run_cli(argv);
    CHECK(r.code == 2);
    CHECK(contains(r.err, "not both"));
  }
  CHECK(run_cli({"run", "--weights", dir / "w.h5", "--camera", "--camera"}).code == 2);
  CHECK(run_cli({"run", "--weights", dir / "w.h5", "--camera", "--duration", "0s"}).code == 2);
  CHECK(run_cli({"run", "--weights", dir / "w.h5", "--camera", "--out", dir / "p.txt"}).code == 2);
  CHECK(run_cli({"run", "--weights", dir / "w.h5", dir / "rec.txt", "--duration", "1s"}).code == 2);
}
