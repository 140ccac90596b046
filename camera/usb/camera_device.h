// What the record loop needs from a camera, whichever model: start streaming decoded events
// into a sink, stop, and say how the stream ended.
#pragma once
#include <functional>
#include <span>
#include <string>

#include "camera/event.h"
#include "camera/usb/decoder_stats.h"
#include "camera/usb/transport.h"

namespace yelan::camera::usb {

class CameraDevice {
 public:
  using EventSink = std::function<void(std::span<const Event>)>;

  virtual ~CameraDevice() = default;
  // Starts streaming; decoded events reach `sink` from inside Transport::poll().
  virtual void start(EventSink sink) = 0;
  // Stops the device (skipped when it is gone) and the transfers. Never throws.
  virtual void stop() noexcept = 0;
  virtual const std::string& error() const = 0;  // why the stream ended early, else empty
  virtual const DecoderStats& stats() const = 0;
  virtual std::uint16_t width() const = 0;
  virtual std::uint16_t height() const = 0;
};

// One 32-bit configuration value over vendor request 0xBF (README.md): wValue = module,
// wIndex = parameter (16 bits: DVXplorer sensor registers use the whole range), 4 data
// bytes big-endian. Throw UsbError.
void config_write(Transport& t, std::uint8_t module, std::uint16_t param, std::uint32_t value);
std::uint32_t config_read(Transport& t, std::uint8_t module, std::uint16_t param);

}  // namespace yelan::camera::usb
