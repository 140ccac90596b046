// DVXplorer control over a Transport: read the device description, bring up the Samsung
// sensor (bias generator, readout, timing, cropper and activity filter off), start and stop
// streaming, and decode bulk data through DvxplorerDecoder. Every request goes through
// Transport, so tests see the exact control transfers. README.md lists the sequence.
#pragma once
#include <chrono>
#include <functional>

#include "camera/usb/camera_device.h"
#include "camera/usb/dvxplorer_decoder.h"

namespace yelan::camera::usb {

struct DvxplorerInfo {
  std::uint32_t logic_version = 0, chip_id = 0;
  std::uint16_t width = 0, height = 0;  // after the orientation swap
  bool invert_xy = false;
  double usb_clock_mhz = 0;
};

class DvxplorerDevice final : public CameraDevice {
 public:
  using Sleep = std::function<void(std::chrono::milliseconds)>;

  explicit DvxplorerDevice(Transport& transport, Sleep sleep = {});
  ~DvxplorerDevice() override;  // puts the sensor back in reset
  DvxplorerDevice(const DvxplorerDevice&) = delete;
  DvxplorerDevice& operator=(const DvxplorerDevice&) = delete;

  // Reads SYSINFO and the DVS geometry, then powers the sensor and loads its start-up
  // registers. Throws UsbError for an unknown chip or an absurd size.
  const DvxplorerInfo& open();
  const DvxplorerInfo& info() const { return info_; }
  // The default readout configuration: simple biases "default", global hold, no
  // subsampling, no area blocking, cropper and activity filter bypassed.
  void configure();
  void start(EventSink sink) override;
  void stop() noexcept override;

  const std::string& error() const override { return error_; }
  const DecoderStats& stats() const override { return decoder_.stats(); }
  std::uint16_t width() const override { return info_.width; }
  std::uint16_t height() const override { return info_.height; }

 private:
  void sensor(std::uint16_t reg, std::uint32_t value);
  // Read-modify-write of one sensor register: clears `clear`, then sets `set`.
  void sensor_update(std::uint16_t reg, std::uint32_t clear, std::uint32_t set);
  void simple_biases();
  void stop_modules();

  Transport& transport_;
  Sleep sleep_;
  DvxplorerInfo info_;
  DvxplorerDecoder decoder_;
  std::vector<Event> batch_;
  std::string error_;
  bool powered_ = false, streaming_ = false;
};

}  // namespace yelan::camera::usb
