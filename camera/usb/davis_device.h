// DAVIS346 control over a Transport: the default configuration (biases, chip register,
// FPGA modules with APS and IMU off) and turning bulk data into events through
// DavisDecoder. open(), start() and stop() are InivationDevice's; every request goes
// through Transport, so tests see the exact control transfers.
#pragma once
#include "camera/usb/davis_decoder.h"
#include "camera/usb/inivation_device.h"

namespace yelan::camera::usb {

using DavisInfo = InivationInfo;

struct DavisConfig {
  bool aps = false;  // frames: off by default (this engine uses events only)
  bool imu = false;  // accelerometer, gyroscope, temperature: off by default
  int early_packet_delay_us = 1000;  // the device ships a short USB packet after this long
};

class DavisDevice final : public InivationDevice {
 public:
  explicit DavisDevice(Transport& transport, Sleep sleep = {});
  ~DavisDevice() override { close(); }

  void configure(const DavisConfig& config = {});
  const DecoderStats& stats() const override { return decoder_.stats(); }

 private:
  void reset_decoder(std::uint16_t columns, std::uint16_t rows, bool invert_xy) override {
    decoder_ = DavisDecoder(columns, rows, invert_xy);
  }
  void decode(std::span<const std::uint8_t> bytes, std::vector<Event>& out) override { decoder_.feed(bytes, out); }
  void start_sensor() override;  // APS and IMU when configured

  DavisConfig config_;
  DavisDecoder decoder_;
};

}  // namespace yelan::camera::usb
