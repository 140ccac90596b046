// Transport over libusb-1.0 for attached cameras, and enumeration of the cameras present.
// Callbacks run on the thread calling poll(); nothing here starts threads of its own.
#pragma once
#include <memory>

#include "camera/usb/transport.h"

namespace yelan::camera::usb {

// The DAVIS346 and DVXplorer cameras attached now (empty when there are none). Throws
// UsbError only when libusb itself cannot start.
std::vector<DeviceInfo> list_devices();

class LibusbTransport final : public Transport {
 public:
  // Opens the camera at device.bus/device.address, selects configuration 1 and claims
  // interface 0. Throws UsbError naming the device and the libusb error.
  explicit LibusbTransport(const DeviceInfo& device);
  ~LibusbTransport() override;
  LibusbTransport(const LibusbTransport&) = delete;
  LibusbTransport& operator=(const LibusbTransport&) = delete;

  void control_out(std::uint8_t request, std::uint16_t value, std::uint16_t index,
                   std::span<const std::uint8_t> data) override;
  std::vector<std::uint8_t> control_in(std::uint8_t request, std::uint16_t value,
                                       std::uint16_t index, std::size_t length) override;
  void clear_halt(std::uint8_t endpoint) override;
  void start_bulk_in(std::uint8_t endpoint, std::size_t size, int count, DataCallback on_data,
                     ErrorCallback on_error) override;
  void stop_bulk_in() noexcept override;
  void poll(std::chrono::milliseconds timeout) override;
  StreamState state() const override;

  struct Impl;  // libusb state; public so the C callback in the .cpp can reach it

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace yelan::camera::usb
