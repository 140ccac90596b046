#include "camera/usb/fake_transport.h"

#include "camera/usb/protocol.h"

namespace yelan::camera::usb {

void FakeTransport::set_config(std::uint16_t module, std::uint16_t param, std::uint32_t value) {
  config_[{module, param}] = value;
}

std::uint32_t FakeTransport::config(std::uint16_t module, std::uint16_t param) const {
  auto it = config_.find({module, param});
  return it == config_.end() ? 0 : it->second;
}

void FakeTransport::queue_buffer(std::vector<std::uint8_t> bytes) { queue_.push_back(std::move(bytes)); }

void FakeTransport::control_out(std::uint8_t request, std::uint16_t value, std::uint16_t index,
                                std::span<const std::uint8_t> data) {
  if (controls_fail_ || state_ == StreamState::disconnected)
    throw UsbError("control transfer failed: device disconnected");
  controls_.push_back({true, request, value, index, {data.begin(), data.end()}});
  if (request == kRequestConfig && data.size() == 4)
    config_[{value, index}] = (std::uint32_t(data[0]) << 24) | (std::uint32_t(data[1]) << 16) |
                              (std::uint32_t(data[2]) << 8) | data[3];
}

std::vector<std::uint8_t> FakeTransport::control_in(std::uint8_t request, std::uint16_t value,
                                                    std::uint16_t index, std::size_t length) {
  if (controls_fail_ || state_ == StreamState::disconnected)
    throw UsbError("control transfer failed: device disconnected");
  std::vector<std::uint8_t> out(length, 0);
  if (request == kRequestConfig && length == 4) {
    const std::uint32_t v = config(value, index);
    out = {std::uint8_t(v >> 24), std::uint8_t(v >> 16), std::uint8_t(v >> 8), std::uint8_t(v)};
  }
  controls_.push_back({false, request, value, index, out});
  return out;
}

void FakeTransport::clear_halt(std::uint8_t) { ++clear_halts_; }

void FakeTransport::start_bulk_in(std::uint8_t, std::size_t, int, DataCallback on_data,
                                  ErrorCallback on_error) {
  on_data_ = std::move(on_data);
  on_error_ = std::move(on_error);
  running_ = true;
  state_ = StreamState::streaming;
}

void FakeTransport::stop_bulk_in() noexcept {
  running_ = false;
  if (state_ == StreamState::streaming) state_ = StreamState::idle;
}

void FakeTransport::poll(std::chrono::milliseconds) {
  if (!running_ || state_ != StreamState::streaming) return;
  if (!queue_.empty()) {
    std::vector<std::uint8_t> buf = std::move(queue_.front());
    queue_.pop_front();
    on_data_(buf);
    return;
  }
  if (unplug_) {
    state_ = StreamState::disconnected;
    if (on_error_) on_error_(state_, "device disconnected (LIBUSB_TRANSFER_NO_DEVICE)");
  }
}

}  // namespace yelan::camera::usb
