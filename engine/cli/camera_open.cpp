#include "engine/cli/camera_open.h"

#include <charconv>
#include <cstdio>
#include <stdexcept>

#include "camera/usb/davis_device.h"
#include "camera/usb/dvxplorer_device.h"
#include "engine/cli/args.h"

namespace yelan::cli {
namespace {

namespace usb = camera::usb;

volatile std::sig_atomic_t g_interrupted = 0;
extern "C" void on_interrupt(int) { g_interrupted = 1; }

}  // namespace

std::string describe_camera(const usb::DeviceInfo& d) {
  char where[48];
  std::snprintf(where, sizeof where, "bus %03u address %03u", d.bus, d.address);
  return std::string(usb::model_name(d.model)) + "  " + where + "  serial " + (d.serial.empty() ? "?" : d.serial) +
         "  firmware " + std::to_string(d.firmware) + (d.note.empty() ? "" : "  (" + d.note + ")");
}

OpenCamera open_camera(const std::optional<std::string>& serial) {
  std::vector<usb::DeviceInfo> found = usb::list_devices();
  if (found.empty()) throw std::runtime_error(kNoCamera);
  const usb::DeviceInfo* chosen = &found.front();
  if (serial) {
    chosen = nullptr;
    std::string seen;
    for (const usb::DeviceInfo& d : found) {
      if (d.serial == *serial) chosen = &d;
      seen += (seen.empty() ? "" : ", ") + (d.serial.empty() ? std::string("?") : d.serial);
    }
    if (!chosen) throw std::runtime_error("no camera with serial '" + *serial + "' (attached: " + seen + ")");
  }
  OpenCamera cam;
  cam.info = *chosen;
  cam.transport = std::make_unique<usb::LibusbTransport>(cam.info);
  auto chip = [](const auto& info) {
    return "chip " + std::to_string(info.chip_id) + ", logic revision " + std::to_string(info.logic_version);
  };
  if (cam.info.model == usb::Model::davis346) {
    auto davis = std::make_unique<usb::DavisDevice>(*cam.transport);
    cam.chip = chip(davis->open());
    davis->configure();
    cam.device = std::move(davis);
  } else {
    auto dvx = std::make_unique<usb::DvxplorerDevice>(*cam.transport);
    cam.chip = chip(dvx->open());
    dvx->configure();
    cam.device = std::move(dvx);
  }
  return cam;
}

InterruptGuard::InterruptGuard() {
  g_interrupted = 0;
  struct sigaction sa {};
  sa.sa_handler = on_interrupt;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, &old_int_);
  sigaction(SIGTERM, &sa, &old_term_);
}

InterruptGuard::~InterruptGuard() {
  sigaction(SIGINT, &old_int_, nullptr);
  sigaction(SIGTERM, &old_term_, nullptr);
}

bool InterruptGuard::interrupted() { return g_interrupted != 0; }

std::function<bool()> until_stopped(std::optional<std::chrono::milliseconds> duration) {
  return [duration, start = std::optional<std::chrono::steady_clock::time_point>()]() mutable {
    if (g_interrupted) return false;
    if (!start) start = std::chrono::steady_clock::now();
    return !duration || std::chrono::steady_clock::now() - *start < *duration;
  };
}

}  // namespace yelan::cli
