// `yelan run --camera`: events from a camera, as they arrive, into the pose pipeline until
// told to stop (--duration, Ctrl-C) or until the camera stops sending (unplugged, USB
// failure). The camera is anything behind camera::usb::CameraDevice and Transport: the real
// libusb one, or a scripted FakeTransport in tests.
#pragma once
#include <functional>
#include <ostream>
#include <string>

#include "camera/usb/camera_device.h"
#include "engine/cli/run_output.h"

namespace yelan::cli {

struct LiveRun {
  RunSetup setup;
  std::string camera_name;  // for the messages
  bool progress = false;    // a live status line on `err` (a terminal), rewritten in place
};

// `device` must be open and configured; `keep_going` is asked between polls. Outputs are
// written on every way out, exceptions included. Returns 0 when stopped by `keep_going`,
// 1 (with a message naming the failure, the events and poses so far) when the camera
// stopped sending.
int run_live(camera::usb::CameraDevice& device, camera::usb::Transport& transport, const LiveRun& live,
             const std::function<bool()>& keep_going, std::ostream& out, std::ostream& err);

}  // namespace yelan::cli
