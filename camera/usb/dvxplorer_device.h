// DVXplorer control over a Transport: the Samsung sensor's bring-up in open() (bias
// generator, readout, timing, cropper and activity filter off), its default readout, its
// streaming mode around InivationDevice's start() and stop(), and bulk data decoded through
// DvxplorerDecoder. Every request goes through Transport, so tests see the exact control
// transfers. README.md lists the sequence.
#pragma once
#include "camera/usb/dvxplorer_decoder.h"
#include "camera/usb/inivation_device.h"

namespace yelan::camera::usb {

using DvxplorerInfo = InivationInfo;

class DvxplorerDevice final : public InivationDevice {
 public:
  explicit DvxplorerDevice(Transport& transport, Sleep sleep = {});
  ~DvxplorerDevice() override { close(); }  // puts the sensor back in reset

  // The default readout configuration: simple biases "default", global hold, no
  // subsampling, no area blocking, cropper and activity filter bypassed.
  void configure();
  const DecoderStats& stats() const override { return decoder_.stats(); }

 private:
  void reset_decoder(std::uint16_t columns, std::uint16_t rows, bool invert_xy) override {
    decoder_ = DvxplorerDecoder(columns, rows, invert_xy);
  }
  void decode(std::span<const std::uint8_t> bytes, std::vector<Event>& out) override { decoder_.feed(bytes, out); }
  void bring_up() override;      // powers the sensor and loads its start-up registers
  void start_sensor() override;  // timestamp reset, stream mode
  void stop_sensor() override;   // sensor off

  void sensor(std::uint16_t reg, std::uint32_t value);
  // Read-modify-write of one sensor register: clears `clear`, then sets `set`.
  void sensor_update(std::uint16_t reg, std::uint32_t clear, std::uint32_t set);

  DvxplorerDecoder decoder_;
};

}  // namespace yelan::camera::usb
