// A scripted Transport for tests: records every control transfer, keeps config writes in a
// register table that config reads answer from (like the FPGA and sensor registers), and
// replays bulk buffers one per poll(), optionally followed by an unplug.
#pragma once
#include <deque>
#include <map>

#include "camera/usb/transport.h"

namespace yelan::camera::usb {

struct ControlRecord {
  bool out;  // true: host to device
  std::uint8_t request;
  std::uint16_t value, index;
  std::vector<std::uint8_t> data;  // payload sent (out) or returned (in)
};

class FakeTransport final : public Transport {
 public:
  // Control transfers, all recorded, and the register table that config reads answer from.
  void control_out(std::uint8_t request, std::uint16_t value, std::uint16_t index,
                   std::span<const std::uint8_t> data) override;
  std::vector<std::uint8_t> control_in(std::uint8_t request, std::uint16_t value,
                                       std::uint16_t index, std::size_t length) override;
  const std::vector<ControlRecord>& controls() const { return controls_; }
  // Value a config read (module, parameter) returns until written; unset registers read 0.
  void set_config(std::uint16_t module, std::uint16_t param, std::uint32_t value);
  std::uint32_t config(std::uint16_t module, std::uint16_t param) const;
  // Makes every later control transfer fail as if the device were gone.
  void fail_controls() { controls_fail_ = true; }

  // The data endpoint: queued buffers come back one per poll(), then optionally an unplug.
  void clear_halt(std::uint8_t endpoint) override;
  int clear_halt_calls() const { return clear_halts_; }
  void start_bulk_in(std::uint8_t endpoint, std::size_t size, int count, DataCallback on_data,
                     ErrorCallback on_error) override;
  bool bulk_running() const { return running_; }
  void stop_bulk_in() noexcept override;
  void poll(std::chrono::milliseconds timeout) override;
  StreamState state() const override { return state_; }
  void queue_buffer(std::vector<std::uint8_t> bytes);
  std::size_t pending_buffers() const { return queue_.size(); }
  // After the queued buffers, report the device as unplugged (LIBUSB_TRANSFER_NO_DEVICE).
  void unplug_after_queue() { unplug_ = true; }

 private:
  std::map<std::pair<std::uint16_t, std::uint16_t>, std::uint32_t> config_;
  std::deque<std::vector<std::uint8_t>> queue_;
  std::vector<ControlRecord> controls_;
  DataCallback on_data_;
  ErrorCallback on_error_;
  StreamState state_ = StreamState::idle;
  bool unplug_ = false, controls_fail_ = false, running_ = false;
  int clear_halts_ = 0;
};

}  // namespace yelan::camera::usb
