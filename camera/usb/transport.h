// The USB transport the driver talks through: vendor control transfers for configuration
// and asynchronous bulk IN transfers for event data. libusb implements it for real cameras
// (libusb_transport.h); FakeTransport (fake_transport.h) replays byte buffers in tests.
#pragma once
#include <chrono>
#include <cstdint>
#include <functional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace yelan::camera::usb {

enum class Model { davis346, dvxplorer };
const char* model_name(Model m);

// One attached camera as enumeration sees it.
struct DeviceInfo {
  Model model = Model::davis346;
  std::uint16_t vendor_id = 0, product_id = 0;
  std::uint8_t bus = 0, address = 0;
  int firmware = -1;   // bcdDevice low byte, the USB firmware version
  std::string serial;  // empty when the device could not be opened to read it
  std::string note;    // why the serial is missing (e.g. permissions), else empty
};

// A USB failure (control transfer refused, device gone). Runtime error: the CLI exits 1.
struct UsbError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Where the data stream stands. `disconnected` and `failed` are terminal: the transport
// delivers no more data, but what it delivered before stays valid.
enum class StreamState { idle, streaming, disconnected, failed };

class Transport {
 public:
  using DataCallback = std::function<void(std::span<const std::uint8_t>)>;
  using ErrorCallback = std::function<void(StreamState, const std::string&)>;

  virtual ~Transport() = default;

  // Vendor request OUT (host to device) with `data` as payload. Throws UsbError.
  virtual void control_out(std::uint8_t request, std::uint16_t value, std::uint16_t index,
                           std::span<const std::uint8_t> data) = 0;
  // Vendor request IN reading exactly `length` bytes. Throws UsbError.
  virtual std::vector<std::uint8_t> control_in(std::uint8_t request, std::uint16_t value,
                                               std::uint16_t index, std::size_t length) = 0;
  // Clears a halt/stall on an endpoint before streaming starts. Throws UsbError.
  virtual void clear_halt(std::uint8_t endpoint) = 0;

  // Queues `count` bulk IN transfers of `size` bytes on `endpoint`. Completed buffers go to
  // on_data; the first terminal problem (device unplugged, transfer error) goes to on_error
  // once. Both run on the thread that calls poll().
  virtual void start_bulk_in(std::uint8_t endpoint, std::size_t size, int count,
                             DataCallback on_data, ErrorCallback on_error) = 0;
  // Cancels the bulk transfers and waits (bounded) until all have come back. Never throws.
  virtual void stop_bulk_in() noexcept = 0;
  // Handles USB events for at most `timeout`, running the callbacks.
  virtual void poll(std::chrono::milliseconds timeout) = 0;
  virtual StreamState state() const = 0;
};

}  // namespace yelan::camera::usb
