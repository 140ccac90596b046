// What the DAVIS346 and DVXplorer devices share. Both boards carry iniVation's FPGA logic
// (README.md: the same modules and parameters), so reading SYSINFO and the DVS geometry,
// the acquisition sequence around the data path (USB FIFO, multiplexer, timestamps, DVS),
// the bulk stream and the unplug path are written once here. A model brings its chip
// check, its start-up registers, its decoder and the steps it adds to open, start and stop.
#pragma once
#include <chrono>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "camera/usb/camera_device.h"

namespace yelan::camera::usb {

// What open() reads from SYSINFO and the DVS module.
struct InivationInfo {
  std::uint32_t logic_version = 0, chip_id = 0;
  std::uint16_t width = 0, height = 0;  // after the orientation swap
  bool invert_xy = false;
  double usb_clock_mhz = 0;  // actual clock = nominal * deviation / 1000
};

// Where the shared sequences branch by model.
struct InivationModel {
  const char* family;       // "unsupported <family> chip identifier N"
  bool (*known_chip)(std::uint32_t chip_id);
  const char* known_chips;  // "(this driver knows <known_chips>)"
  bool has_aps;             // a frame module, switched off with the rest
  // DAVIS: the bias generator (MUX run chip) goes on in start() and off with the data path.
  // DVXplorer: the sensor leaves reset in open() (power_chip()) and goes back in close().
  bool chip_runs_while_streaming;
};

class InivationDevice : public CameraDevice {
 public:
  using Sleep = std::function<void(std::chrono::milliseconds)>;

  InivationDevice(const InivationDevice&) = delete;
  InivationDevice& operator=(const InivationDevice&) = delete;

  // One 32-bit configuration write / read (vendor request 0xBF). Throw UsbError.
  void config_set(std::uint8_t module, std::uint16_t param, std::uint32_t value);
  std::uint32_t config_get(std::uint8_t module, std::uint16_t param);

  // Reads SYSINFO and the DVS geometry, then runs the model's bring_up(). Throws UsbError
  // for a chip the model does not know or an absurd size.
  const InivationInfo& open();
  const InivationInfo& info() const { return info_; }
  void start(EventSink sink) final;
  void stop() noexcept final;

  StreamState state() const { return transport_.state(); }
  const std::string& error() const final { return error_; }
  std::uint16_t width() const final { return info_.width; }
  std::uint16_t height() const final { return info_.height; }

 protected:
  // `sleep` waits between start-up steps (bias settling); tests pass a no-op.
  InivationDevice(Transport& transport, Sleep sleep, const InivationModel& model);

  // stop(), then a sensor powered since open() back in reset. Each model's destructor calls
  // it: stop() runs the model's hooks, which ~InivationDevice could no longer reach.
  void close() noexcept;
  void require_open(const char* step) const;  // throws "<step> before open()"
  void wait(std::chrono::milliseconds duration) { sleep_(duration); }
  void power_chip();  // MUX run chip = 1, undone by close()
  // The FPGA counts the early-packet delay (a short USB packet after this long) in USB clock cycles.
  void set_early_packet_delay(int microseconds);

  // The model's own parts. Geometry as addressed on the wire (before the swap).
  virtual void reset_decoder(std::uint16_t columns, std::uint16_t rows, bool invert_xy) = 0;
  virtual void decode(std::span<const std::uint8_t> bytes, std::vector<Event>& out) = 0;
  virtual void bring_up() {}      // last step of open()
  virtual void start_sensor() {}  // last step of start(), after DVS on
  virtual void stop_sensor() {}   // first step of stop() while the device is there

 private:
  void stop_modules();

  Transport& transport_;
  Sleep sleep_;
  InivationModel model_;
  InivationInfo info_;
  std::vector<Event> batch_;
  std::string error_;
  bool streaming_ = false, chip_powered_ = false;
};

}  // namespace yelan::camera::usb
