#include "camera/usb/libusb_transport.h"

#include <libusb.h>

#include <sys/time.h>

#include <cstdio>
#include <exception>
#include <utility>

#include "camera/usb/protocol.h"

namespace yelan::camera::usb {
namespace {

constexpr unsigned kControlTimeoutMs = 1000;
constexpr int kCancelWaitRounds = 50;  // x 100 ms: how long stop_bulk_in waits for cancels

std::string usb_error(int code) { return libusb_error_name(code); }

std::string device_name(const DeviceInfo& d) {
  char buf[80];
  std::snprintf(buf, sizeof buf, "%s at bus %u address %u", model_name(d.model), d.bus, d.address);
  return buf;
}

// One libusb context per object, so independent users never share state.
struct Context {
  libusb_context* ctx = nullptr;
  Context() {
    if (int r = libusb_init(&ctx); r != LIBUSB_SUCCESS) {
      ctx = nullptr;
      throw UsbError("libusb could not start: " + usb_error(r));
    }
  }
  ~Context() {
    if (ctx) libusb_exit(ctx);
  }
  Context(const Context&) = delete;
  Context& operator=(const Context&) = delete;
};

struct DeviceList {
  libusb_device** list = nullptr;
  ssize_t count = 0;
  explicit DeviceList(libusb_context* ctx) {
    count = libusb_get_device_list(ctx, &list);
    if (count < 0) {
      list = nullptr;
      throw UsbError("libusb could not list devices: " + usb_error(static_cast<int>(count)));
    }
  }
  ~DeviceList() {
    if (list) libusb_free_device_list(list, 1);
  }
  DeviceList(const DeviceList&) = delete;
  DeviceList& operator=(const DeviceList&) = delete;
};

bool known_camera(const libusb_device_descriptor& d, Model* model) {
  if (d.idVendor != kVendorId) return false;
  if (d.idProduct == kDavis346ProductId) {
    *model = Model::davis346;
    return true;
  }
  if (d.idProduct == kDvxplorerProductId) {
    *model = Model::dvxplorer;
    return true;
  }
  return false;
}

struct TransferDeleter {
  void operator()(libusb_transfer* t) const { libusb_free_transfer(t); }
};

void LIBUSB_CALL on_transfer(libusb_transfer* t);

}  // namespace

struct LibusbTransport::Impl {
  struct Slot {
    Impl* owner = nullptr;
    std::unique_ptr<libusb_transfer, TransferDeleter> transfer;
    std::vector<std::uint8_t> buffer;
    bool in_flight = false;
  };

  Context context;
  DeviceInfo device;
  libusb_device_handle* handle = nullptr;
  bool claimed = false;
  std::vector<std::unique_ptr<Slot>> slots;
  DataCallback on_data;
  ErrorCallback on_error;
  StreamState state = StreamState::idle;
  bool running = false;
  int in_flight = 0;
  std::exception_ptr callback_error;  // thrown by a user callback inside libusb; poll() rethrows

  ~Impl() {
    if (claimed) libusb_release_interface(handle, kInterface);
    if (handle) libusb_close(handle);
  }

  // The first terminal problem ends streaming and is reported once.
  void terminal(StreamState s, const std::string& why) {
    running = false;
    if (state == StreamState::disconnected || state == StreamState::failed) return;
    state = s;
    if (!on_error) return;
    try {
      on_error(s, why);
    } catch (...) {
      if (!callback_error) callback_error = std::current_exception();
    }
  }

  [[noreturn]] void control_failed(int r, const char* what, std::uint16_t value, std::uint16_t index) {
    if (r == LIBUSB_ERROR_NO_DEVICE) terminal(StreamState::disconnected, "device disconnected");
    throw UsbError(std::string(what) + " (module " + std::to_string(value) + ", parameter " +
                   std::to_string(index) + ") on " + device_name(device) + " failed: " + usb_error(r));
  }

  void completed(Slot& slot) {
    libusb_transfer* t = slot.transfer.get();
    switch (t->status) {
      case LIBUSB_TRANSFER_COMPLETED:
        if (running && on_data && t->actual_length > 0) {
          try {
            on_data(std::span<const std::uint8_t>(slot.buffer.data(), static_cast<std::size_t>(t->actual_length)));
          } catch (...) {
            if (!callback_error) callback_error = std::current_exception();
            running = false;
          }
        }
        [[fallthrough]];
      case LIBUSB_TRANSFER_TIMED_OUT:
        if (running) {
          const int r = libusb_submit_transfer(t);
          if (r == LIBUSB_SUCCESS) return;  // still in flight
          slot.in_flight = false;
          --in_flight;
          terminal(r == LIBUSB_ERROR_NO_DEVICE ? StreamState::disconnected : StreamState::failed,
                   "resubmitting a bulk transfer failed: " + usb_error(r));
          return;
        }
        break;
      case LIBUSB_TRANSFER_NO_DEVICE:
        slot.in_flight = false;
        --in_flight;
        terminal(StreamState::disconnected, "device disconnected (LIBUSB_TRANSFER_NO_DEVICE)");
        return;
      case LIBUSB_TRANSFER_CANCELLED:
        break;
      default:  // ERROR, STALL, OVERFLOW
        slot.in_flight = false;
        --in_flight;
        terminal(StreamState::failed, "bulk transfer failed with libusb status " + std::to_string(t->status));
        return;
    }
    slot.in_flight = false;
    --in_flight;
  }
};

namespace {

void LIBUSB_CALL on_transfer(libusb_transfer* t) {
  auto* slot = static_cast<LibusbTransport::Impl::Slot*>(t->user_data);
  slot->owner->completed(*slot);
}

}  // namespace

std::vector<DeviceInfo> list_devices() {
  Context context;
  DeviceList devices(context.ctx);
  std::vector<DeviceInfo> found;
  for (ssize_t i = 0; i < devices.count; ++i) {
    libusb_device* dev = devices.list[i];
    libusb_device_descriptor desc{};
    Model model{};
    if (libusb_get_device_descriptor(dev, &desc) != LIBUSB_SUCCESS || !known_camera(desc, &model)) continue;
    DeviceInfo info;
    info.model = model;
    info.vendor_id = desc.idVendor;
    info.product_id = desc.idProduct;
    info.bus = libusb_get_bus_number(dev);
    info.address = libusb_get_device_address(dev);
    info.firmware = desc.bcdDevice & 0xFF;
    libusb_device_handle* h = nullptr;
    if (int r = libusb_open(dev, &h); r != LIBUSB_SUCCESS) {
      info.note = "cannot open to read the serial (" + usb_error(r) +
                  (r == LIBUSB_ERROR_ACCESS ? "; a udev rule for vendor 152a is needed)" : ")");
    } else {
      unsigned char serial[64] = {};
      const int n = desc.iSerialNumber == 0 ? 0
                    : libusb_get_string_descriptor_ascii(h, desc.iSerialNumber, serial, sizeof serial - 1);
      if (n > 0) info.serial.assign(reinterpret_cast<const char*>(serial), static_cast<std::size_t>(n));
      else info.note = "serial number not readable";
      libusb_close(h);
    }
    found.push_back(std::move(info));
  }
  return found;
}

LibusbTransport::LibusbTransport(const DeviceInfo& device) : impl_(std::make_unique<Impl>()) {
  Impl& s = *impl_;
  s.device = device;
  const std::string name = device_name(device);
  {
    DeviceList devices(s.context.ctx);
    for (ssize_t i = 0; i < devices.count && !s.handle; ++i) {
      libusb_device* dev = devices.list[i];
      libusb_device_descriptor desc{};
      Model model{};
      if (libusb_get_bus_number(dev) != device.bus || libusb_get_device_address(dev) != device.address) continue;
      if (libusb_get_device_descriptor(dev, &desc) != LIBUSB_SUCCESS || !known_camera(desc, &model))
        throw UsbError("the device at bus " + std::to_string(device.bus) + " address " +
                       std::to_string(device.address) + " is not a DAVIS346/DVXplorer (unplugged and replaced?)");
      if (int r = libusb_open(dev, &s.handle); r != LIBUSB_SUCCESS) {
        s.handle = nullptr;
        throw UsbError("cannot open " + name + ": " + usb_error(r) +
                       (r == LIBUSB_ERROR_ACCESS ? " (a udev rule for vendor 152a is needed)" : ""));
      }
    }
  }
  if (!s.handle) throw UsbError(name + " is no longer attached");
  int config = 0;
  if (int r = libusb_get_configuration(s.handle, &config); r != LIBUSB_SUCCESS)
    throw UsbError("cannot read the configuration of " + name + ": " + usb_error(r));
  if (config != kConfiguration)
    if (int r = libusb_set_configuration(s.handle, kConfiguration); r != LIBUSB_SUCCESS)
      throw UsbError("cannot select configuration 1 of " + name + ": " + usb_error(r));
  if (int r = libusb_claim_interface(s.handle, kInterface); r != LIBUSB_SUCCESS)
    throw UsbError("cannot claim interface 0 of " + name + " (in use by another program?): " + usb_error(r));
  s.claimed = true;
}

LibusbTransport::~LibusbTransport() { stop_bulk_in(); }

void LibusbTransport::control_out(std::uint8_t request, std::uint16_t value, std::uint16_t index,
                                  std::span<const std::uint8_t> data) {
  std::vector<std::uint8_t> copy(data.begin(), data.end());  // libusb wants a mutable buffer
  const int r = libusb_control_transfer(impl_->handle, kRequestTypeOut, request, value, index, copy.data(),
                                        static_cast<std::uint16_t>(copy.size()), kControlTimeoutMs);
  if (r < 0) impl_->control_failed(r, "config write", value, index);
  if (static_cast<std::size_t>(r) != copy.size())
    throw UsbError("config write (module " + std::to_string(value) + ", parameter " + std::to_string(index) +
                   ") sent " + std::to_string(r) + " of " + std::to_string(copy.size()) + " bytes");
}

std::vector<std::uint8_t> LibusbTransport::control_in(std::uint8_t request, std::uint16_t value,
                                                      std::uint16_t index, std::size_t length) {
  std::vector<std::uint8_t> out(length);
  const int r = libusb_control_transfer(impl_->handle, kRequestTypeIn, request, value, index, out.data(),
                                        static_cast<std::uint16_t>(length), kControlTimeoutMs);
  if (r < 0) impl_->control_failed(r, "config read", value, index);
  out.resize(static_cast<std::size_t>(r));
  return out;
}

void LibusbTransport::clear_halt(std::uint8_t endpoint) {
  if (int r = libusb_clear_halt(impl_->handle, endpoint); r != LIBUSB_SUCCESS)
    impl_->control_failed(r, "clearing the data endpoint", endpoint, 0);
}

void LibusbTransport::start_bulk_in(std::uint8_t endpoint, std::size_t size, int count, DataCallback on_data,
                                    ErrorCallback on_error) {
  Impl& s = *impl_;
  if (s.running || s.in_flight > 0) throw UsbError("bulk transfers already running");
  s.slots.clear();
  s.on_data = std::move(on_data);
  s.on_error = std::move(on_error);
  s.callback_error = nullptr;
  s.state = StreamState::streaming;
  s.running = true;
  for (int i = 0; i < count; ++i) {
    auto slot = std::make_unique<Impl::Slot>();
    slot->owner = &s;
    slot->buffer.resize(size);
    slot->transfer.reset(libusb_alloc_transfer(0));
    if (!slot->transfer) break;
    libusb_fill_bulk_transfer(slot->transfer.get(), s.handle, endpoint, slot->buffer.data(),
                              static_cast<int>(size), on_transfer, slot.get(), 0);
    const int r = libusb_submit_transfer(slot->transfer.get());
    if (r != LIBUSB_SUCCESS) {
      stop_bulk_in();
      s.state = r == LIBUSB_ERROR_NO_DEVICE ? StreamState::disconnected : StreamState::failed;
      throw UsbError("cannot submit bulk transfers on " + device_name(s.device) + ": " + usb_error(r));
    }
    slot->in_flight = true;
    ++s.in_flight;
    s.slots.push_back(std::move(slot));
  }
  if (s.in_flight == 0) {
    s.state = StreamState::failed;
    s.running = false;
    throw UsbError("cannot allocate bulk transfers");
  }
}

void LibusbTransport::stop_bulk_in() noexcept {
  Impl& s = *impl_;
  s.running = false;
  for (auto& slot : s.slots)
    if (slot->in_flight) libusb_cancel_transfer(slot->transfer.get());
  for (int round = 0; round < kCancelWaitRounds && s.in_flight > 0; ++round) {
    timeval tv{0, 100000};
    libusb_handle_events_timeout_completed(s.context.ctx, &tv, nullptr);
  }
  // A transfer libusb never gave back must not be freed under it: leak it deliberately.
  for (auto& slot : s.slots)
    if (slot->in_flight) (void)slot.release();
  s.slots.clear();
  if (s.state == StreamState::streaming) s.state = StreamState::idle;
}

void LibusbTransport::poll(std::chrono::milliseconds timeout) {
  Impl& s = *impl_;
  const auto us = std::chrono::duration_cast<std::chrono::microseconds>(timeout).count();
  timeval tv{static_cast<time_t>(us / 1000000), static_cast<suseconds_t>(us % 1000000)};
  const int r = libusb_handle_events_timeout_completed(s.context.ctx, &tv, nullptr);
  if (r != LIBUSB_SUCCESS && r != LIBUSB_ERROR_INTERRUPTED && r != LIBUSB_ERROR_TIMEOUT)
    s.terminal(r == LIBUSB_ERROR_NO_DEVICE ? StreamState::disconnected : StreamState::failed,
               "handling USB events failed: " + usb_error(r));
  if (s.callback_error) std::rethrow_exception(std::exchange(s.callback_error, nullptr));
}

StreamState LibusbTransport::state() const { return impl_->state; }

}  // namespace yelan::camera::usb
