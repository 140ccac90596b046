#include "engine/cli/run_live.h"

#include <chrono>
#include <iomanip>
#include <sstream>

#include "camera/usb/recorder.h"
#include "engine/cli/cli.h"

namespace yelan::cli {
namespace {

namespace usb = camera::usb;
using Clock = std::chrono::steady_clock;

// The recorder's writer end, feeding the pipeline instead of a file. It runs inside
// Transport::poll(): the bulk transfers still queued keep filling meanwhile, and when the
// pipeline is slower than the camera the camera drops events on its side (USB stall),
// so memory stays bounded.
class PipelineFeed final : public camera::EventWriter {
 public:
  explicit PipelineFeed(RunSession& session) : session_(session) {}
  void write(std::span<const camera::Event> batch) override {
    if (batch.empty()) return;
    events += batch.size();
    last_t = batch.back().t;
    session_.push(batch);
  }
  void close() override {}

  std::uint64_t events = 0;
  std::int64_t last_t = 0;

 private:
  RunSession& session_;
};

std::string seconds(std::int64_t t_us) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(3) << double(t_us) * 1e-6 << " s";
  return o.str();
}

}  // namespace

int run_live(usb::CameraDevice& device, usb::Transport& transport, const LiveRun& live,
             const std::function<bool()>& keep_going, std::ostream& out, std::ostream& err) {
  RunSession session(live.setup, device.width(), device.height(), true);
  PipelineFeed feed(session);
  const auto start = Clock::now();
  auto last_line = start - std::chrono::seconds(1);  // the first line at once: it is running
  auto wall_s = [&] { return std::chrono::duration<double>(Clock::now() - start).count(); };
  auto ask = [&] {
    if (live.progress && Clock::now() - last_line >= std::chrono::milliseconds(500)) {
      last_line = Clock::now();
      const double wall = wall_s();
      err << "\r" << session.poses() << " poses, " << std::fixed << std::setprecision(1)
          << (wall > 0 ? double(session.poses()) / wall : 0.0) << " poses/s, stage 1 on " << std::setprecision(0)
          << 100 * session.stage1_share() << "% of ticks, " << feed.events << " events   " << std::flush;
      err << std::defaultfloat << std::setprecision(6);
    }
    return keep_going();
  };

  // Whatever else goes wrong (a disk full, a bad weights tensor), keep what was computed.
  auto salvage = [&] {
    if (live.progress) err << "\n";
    try {
      session.write_outputs(wall_s(), err);
    } catch (...) {
    }
  };
  std::string failure;
  try {
    const usb::RecordResult r = usb::record(device, transport, feed, ask);
    failure = r.error;
    if (failure.empty() && (transport.state() == usb::StreamState::disconnected ||
                            transport.state() == usb::StreamState::failed))
      failure = "the USB transfers stopped";
  } catch (const usb::UsbError& e) {
    failure = e.what();  // libusb failed while polling: the stream is over, the poses are not
  } catch (...) {
    salvage();
    throw;
  }
  try {
    session.finish(feed.last_t);
  } catch (...) {
    salvage();
    throw;
  }
  const double wall = wall_s();
  if (live.progress) err << "\n";
  session.write_outputs(wall, err);
  session.report(live.camera_name, wall, out);
  if (failure.empty()) return kOk;
  err << "yelan run: the camera stopped sending after " << feed.events << " events at t=" << seconds(feed.last_t)
      << ": " << failure << "; the " << session.poses() << " poses computed are "
      << (live.setup.out ? "written to " + *live.setup.out : std::string("not written (no --out)")) << "\n";
  return kRuntimeError;
}

}  // namespace yelan::cli
