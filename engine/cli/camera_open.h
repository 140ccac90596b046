// What `yelan record` and `yelan run --camera` share: finding and opening an attached
// DAVIS346/DVXplorer (the first one, or the one with a given serial), --duration, and
// stopping cleanly on Ctrl-C or SIGTERM.
#pragma once
#include <chrono>
#include <csignal>
#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "camera/usb/camera_device.h"
#include "camera/usb/libusb_transport.h"

namespace yelan::cli {

inline constexpr const char* kNoCamera =
    "no camera found (looked for iniVation DAVIS346 152a:841a and DVXplorer 152a:8419 on USB)";

// "DAVIS346  bus 001 address 004  serial 00000499  firmware 6".
std::string describe_camera(const camera::usb::DeviceInfo& d);

// A camera opened, configured and ready to start. The device refers to the transport, so
// it is declared after it (destroyed first).
struct OpenCamera {
  camera::usb::DeviceInfo info;
  std::unique_ptr<camera::usb::LibusbTransport> transport;
  std::unique_ptr<camera::usb::CameraDevice> device;
  std::string chip;  // "chip 5, logic revision 18"
};

// Throws std::runtime_error (exit 1) when no camera, or none with this serial, is attached;
// UsbError when it cannot be opened or configured.
OpenCamera open_camera(const std::optional<std::string>& serial);

// While alive, SIGINT and SIGTERM only set a flag (restores the previous handlers after).
class InterruptGuard {
 public:
  InterruptGuard();
  ~InterruptGuard();
  InterruptGuard(const InterruptGuard&) = delete;
  InterruptGuard& operator=(const InterruptGuard&) = delete;
  static bool interrupted();

 private:
  struct sigaction old_int_ {}, old_term_ {};
};

// The acquisition loops' `keep_going`: false once interrupted or when `duration` (from the
// first call on; nullopt: no limit) has passed.
std::function<bool()> until_stopped(std::optional<std::chrono::milliseconds> duration);

}  // namespace yelan::cli
