// DAVIS346 control over a Transport: read the device description, send the default
// configuration (biases, chip register, FPGA modules with APS and IMU off), start and stop
// acquisition, and turn bulk data into events through DavisDecoder. Every request goes
// through Transport, so tests see the exact control transfers.
#pragma once
#include <chrono>
#include <functional>
#include <span>
#include <string>

#include "camera/usb/camera_device.h"
#include "camera/usb/davis_decoder.h"

namespace yelan::camera::usb {

struct DavisInfo {
  std::uint32_t logic_version = 0, chip_id = 0;
  std::uint16_t width = 0, height = 0;  // after the orientation swap
  bool invert_xy = false;
  double usb_clock_mhz = 0;  // actual clock = nominal * deviation / 1000
};

struct DavisConfig {
  bool aps = false;  // frames: off by default (this engine uses events only)
  bool imu = false;  // accelerometer, gyroscope, temperature: off by default
  int early_packet_delay_us = 1000;  // the device ships a short USB packet after this long
};

class DavisDevice final : public CameraDevice {
 public:
  using Sleep = std::function<void(std::chrono::milliseconds)>;

  // `sleep` waits between start-up steps (bias settling); tests pass a no-op.
  explicit DavisDevice(Transport& transport, Sleep sleep = {});
  ~DavisDevice() override;
  DavisDevice(const DavisDevice&) = delete;
  DavisDevice& operator=(const DavisDevice&) = delete;

  // One 32-bit configuration write / read (vendor request 0xBF). Throw UsbError.
  void config_set(std::uint8_t module, std::uint8_t param, std::uint32_t value);
  std::uint32_t config_get(std::uint8_t module, std::uint8_t param);

  // Reads SYSINFO and DVS size/orientation; throws UsbError for a chip that is not a
  // DAVIS346 or an absurd size.
  const DavisInfo& open();
  const DavisInfo& info() const { return info_; }
  void configure(const DavisConfig& config = {});
  void start(EventSink sink) override;
  void stop() noexcept override;

  StreamState state() const { return transport_.state(); }
  const std::string& error() const override { return error_; }
  const DecoderStats& stats() const override { return decoder_.stats(); }
  std::uint16_t width() const override { return info_.width; }
  std::uint16_t height() const override { return info_.height; }

 private:
  void stop_modules();

  Transport& transport_;
  Sleep sleep_;
  DavisInfo info_;
  DavisConfig config_;
  DavisDecoder decoder_;
  std::vector<Event> batch_;
  std::string error_;
  bool streaming_ = false;
};

}  // namespace yelan::camera::usb
