// `yelan devices` and `yelan record`: list attached DAVIS346/DVXplorer cameras, and record
// one of them to an event file through the clean-room libusb driver in camera/usb/.
#include <chrono>
#include <cmath>
#include <optional>

#include "camera/io/event_writer.h"
#include "camera/usb/recorder.h"
#include "engine/cli/args.h"
#include "engine/cli/camera_open.h"
#include "engine/cli/cli.h"
#include "engine/cli/handlers.h"

namespace yelan::cli {

namespace usb = camera::usb;

int cmd_devices(const std::vector<std::string>& args, std::ostream& out, std::ostream&) {
  Args a("devices", args, {}, {});
  a.expect_positionals(0, 0);
  const std::vector<usb::DeviceInfo> found = usb::list_devices();
  if (found.empty()) {
    out << kNoCamera << "\n";
    return kOk;
  }
  for (const usb::DeviceInfo& d : found) out << describe_camera(d) << "\n";
  return kOk;
}

int cmd_record(const std::vector<std::string>& args, std::ostream& out, std::ostream& err) {
  Args a("record", args, {"--duration", "--camera"}, {});
  a.expect_positionals(1, 1);
  const std::string path = a.positionals()[0];
  if (camera::writer_format_for(path).empty())
    throw UsageError("cannot tell the output format of '" + path + "' (use .aedat4, .txt or .yelan.h5)");
  std::optional<std::chrono::milliseconds> duration;
  if (const auto d = a.value("--duration")) duration = std::chrono::milliseconds(std::llround(parse_duration_s(*d) * 1000));

  OpenCamera cam = open_camera(a.value("--camera"));
  usb::CameraDevice* device = cam.device.get();
  camera::StreamInfo stream;
  stream.format = camera::writer_format_for(path);
  stream.width = device->width();
  stream.height = device->height();
  std::unique_ptr<camera::EventWriter> writer = camera::open_event_writer(path, stream);

  InterruptGuard guard;
  const usb::RecordResult r = usb::record(*device, *cam.transport, *writer, until_stopped(duration));

  out << "recorded " << r.events << " events";
  if (r.events > 0) out << " (t " << r.t_first << " .. " << r.t_last << " us)";
  out << " from " << describe_camera(cam.info) << " to " << path
      << (InterruptGuard::interrupted() ? " (interrupted)" : "") << "\n";
  out << "camera: " << cam.chip << ", " << device->width() << "x" << device->height() << "; decoder: " << r.stats.summary()
      << "\n";
  if (!r.error.empty()) {
    err << "yelan record: the camera stream ended early: " << r.error << "; the " << r.events
        << " events decoded before are in " << path << "\n";
    return kRuntimeError;
  }
  return kOk;
}

}  // namespace yelan::cli
