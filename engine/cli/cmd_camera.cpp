// `yelan devices` and `yelan record`: list attached DAVIS346/DVXplorer cameras, and record
// one of them to an event file through the clean-room libusb driver in camera/usb/.
#include <charconv>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <stdexcept>

#include "camera/io/event_writer.h"
#include "camera/usb/davis_device.h"
#include "camera/usb/dvxplorer_device.h"
#include "camera/usb/libusb_transport.h"
#include "camera/usb/protocol.h"
#include "camera/usb/recorder.h"
#include "engine/cli/args.h"
#include "engine/cli/cli.h"
#include "engine/cli/handlers.h"

namespace yelan::cli {
namespace {

namespace usb = camera::usb;

volatile std::sig_atomic_t g_interrupted = 0;
extern "C" void on_sigint(int) { g_interrupted = 1; }

// Restores the previous SIGINT/SIGTERM handlers when recording ends.
class InterruptGuard {
 public:
  InterruptGuard() {
    g_interrupted = 0;
    struct sigaction sa {};
    sa.sa_handler = on_sigint;
    sigemptyset(&sa.sa_mask);
    sigaction(SIGINT, &sa, &old_int_);
    sigaction(SIGTERM, &sa, &old_term_);
  }
  ~InterruptGuard() {
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
  }
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;

 private:
  struct sigaction old_int_ {}, old_term_ {};
};

// "10s", "1.5s", "500ms", "2m", "1h", or a plain number of seconds.
std::chrono::milliseconds parse_duration(const std::string& text) {
  double value = 0;
  const char* end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(text.data(), end, value);
  const std::string unit(ptr, end);
  double ms_per_unit = 0;
  if (unit.empty() || unit == "s") ms_per_unit = 1000;
  else if (unit == "ms") ms_per_unit = 1;
  else if (unit == "m" || unit == "min") ms_per_unit = 60000;
  else if (unit == "h") ms_per_unit = 3600000;
  const double ms = value * ms_per_unit;
  if (ec != std::errc() || ptr == text.data() || ms_per_unit == 0 || !(ms > 0) || ms > 1e12)
    throw UsageError("--duration expects a positive time like 10s, 500ms or 2m, got '" + text + "'");
  return std::chrono::milliseconds(static_cast<std::int64_t>(ms + 0.5));
}

std::string describe(const usb::DeviceInfo& d) {
  char where[48];
  std::snprintf(where, sizeof where, "bus %03u address %03u", d.bus, d.address);
  return std::string(usb::model_name(d.model)) + "  " + where + "  serial " +
         (d.serial.empty() ? "?" : d.serial) + "  firmware " + std::to_string(d.firmware) +
         (d.note.empty() ? "" : "  (" + d.note + ")");
}

const char* kNoCamera =
    "no camera found (looked for iniVation DAVIS346 152a:841a and DVXplorer 152a:8419 on USB)";

}  // namespace

int cmd_devices(const std::vector<std::string>& args, std::ostream& out, std::ostream&) {
  Args a("devices", args, {}, {});
  a.expect_positionals(0, 0);
  const std::vector<usb::DeviceInfo> found = usb::list_devices();
  if (found.empty()) {
    out << kNoCamera << "\n";
    return kOk;
  }
  for (const usb::DeviceInfo& d : found) out << describe(d) << "\n";
  return kOk;
}

int cmd_record(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  Args a("record", args, {"--duration", "--camera"}, {});
  a.expect_positionals(1, 1);
  const std::string path = a.positionals()[0];
  if (camera::writer_format_for(path).empty())
    throw UsageError("cannot tell the output format of '" + path + "' (use .aedat4, .txt or .yelan.h5)");
  const auto duration = a.value("--duration") ? parse_duration(*a.value("--duration"))
                                              : std::chrono::milliseconds::max();

  std::vector<usb::DeviceInfo> found = usb::list_devices();
  if (found.empty()) throw std::runtime_error(kNoCamera);
  const usb::DeviceInfo* chosen = &found.front();
  if (auto serial = a.value("--camera")) {
    chosen = nullptr;
    std::string seen;
    for (const usb::DeviceInfo& d : found) {
      if (d.serial == *serial) chosen = &d;
      seen += (seen.empty() ? "" : ", ") + (d.serial.empty() ? std::string("?") : d.serial);
    }
    if (!chosen) throw std::runtime_error("no camera with serial '" + *serial + "' (attached: " + seen + ")");
  }
  usb::LibusbTransport transport(*chosen);
  std::unique_ptr<usb::CameraDevice> device;
  std::string chip;
  if (chosen->model == usb::Model::davis346) {
    auto davis = std::make_unique<usb::DavisDevice>(transport);
    const usb::DavisInfo& info = davis->open();
    davis->configure();
    chip = "chip " + std::to_string(info.chip_id) + ", logic revision " + std::to_string(info.logic_version);
    device = std::move(davis);
  } else {
    auto dvx = std::make_unique<usb::DvxplorerDevice>(transport);
    const usb::DvxplorerInfo& info = dvx->open();
    dvx->configure();
    chip = "chip " + std::to_string(info.chip_id) + ", logic revision " + std::to_string(info.logic_version);
    device = std::move(dvx);
  }
  camera::StreamInfo stream;
  stream.format = camera::writer_format_for(path);
  stream.width = device->width();
  stream.height = device->height();
  std::unique_ptr<camera::EventWriter> writer = camera::open_event_writer(path, stream);

  InterruptGuard guard;
  const auto start = std::chrono::steady_clock::now();
  auto keep_going = [&] {
    if (g_interrupted) return false;
    if (duration == std::chrono::milliseconds::max()) return true;
    return std::chrono::steady_clock::now() - start < duration;
  };
  const usb::RecordResult r = usb::record(*device, transport, *writer, keep_going);

  out << "recorded " << r.events << " events";
  if (r.events > 0) out << " (t " << r.t_first << " .. " << r.t_last << " us)";
  out << " from " << describe(*chosen) << " to " << path << (g_interrupted ? " (interrupted)" : "") << "\n";
  out << "camera: " << chip << ", " << device->width() << "x" << device->height() << "; decoder: " << r.stats.summary()
      << "\n";
  if (!r.error.empty()) {
    err << "yelan record: the camera stream ended early: " << r.error << "; the " << r.events
        << " events decoded before are in " << path << "\n";
    return kRuntimeError;
  }
  return kOk;
}

}  // namespace yelan::cli
