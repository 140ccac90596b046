#include "camera/usb/inivation_device.h"

#include <cmath>
#include <thread>

#include "camera/usb/protocol.h"

namespace yelan::camera::usb {
namespace {

// Data stream transfers: libcaer's defaults for FX3 boards.
constexpr int kTransferCount = 8;
constexpr std::size_t kTransferSize = 8192;

}  // namespace

InivationDevice::InivationDevice(Transport& transport, Sleep sleep, const InivationModel& model)
    : transport_(transport), sleep_(std::move(sleep)), model_(model) {
  if (!sleep_) sleep_ = [](std::chrono::milliseconds d) { std::this_thread::sleep_for(d); };
}

void InivationDevice::config_set(std::uint8_t module, std::uint16_t param, std::uint32_t value) {
  config_write(transport_, module, param, value);
}

std::uint32_t InivationDevice::config_get(std::uint8_t module, std::uint16_t param) {
  return config_read(transport_, module, param);
}

const InivationInfo& InivationDevice::open() {
  InivationInfo info;
  info.logic_version = config_get(module::sysinfo, sysinfo::logic_version);
  info.chip_id = config_get(module::sysinfo, sysinfo::chip_identifier);
  if (!model_.known_chip(info.chip_id))
    throw UsbError(std::string("unsupported ") + model_.family + " chip identifier " + std::to_string(info.chip_id) +
                   " (this driver knows " + model_.known_chips + ")");
  const std::uint32_t columns = config_get(module::dvs, dvs::size_columns);
  const std::uint32_t rows = config_get(module::dvs, dvs::size_rows);
  if (columns == 0 || rows == 0 || columns > 1024 || rows > 1024)
    throw UsbError("device reports an absurd DVS size " + std::to_string(columns) + "x" + std::to_string(rows));
  info.invert_xy = (config_get(module::dvs, dvs::orientation) & 0x04) != 0;
  info.width = static_cast<std::uint16_t>(info.invert_xy ? rows : columns);
  info.height = static_cast<std::uint16_t>(info.invert_xy ? columns : rows);
  const double usb_clock = config_get(module::sysinfo, sysinfo::usb_clock);
  const double deviation = config_get(module::sysinfo, sysinfo::clock_deviation);
  info.usb_clock_mhz = usb_clock * deviation / 1000.0;
  info_ = info;
  reset_decoder(static_cast<std::uint16_t>(columns), static_cast<std::uint16_t>(rows), info.invert_xy);
  bring_up();
  return info_;
}

void InivationDevice::require_open(const char* step) const {
  if (info_.width == 0) throw UsbError(std::string(step) + " before open()");
}

void InivationDevice::power_chip() {
  config_set(module::mux, mux::run_chip, 1);
  chip_powered_ = true;
}

void InivationDevice::set_early_packet_delay(int microseconds) {
  const double cycles = std::round(microseconds * info_.usb_clock_mhz);
  config_set(module::usb, usbmod::early_packet_delay, static_cast<std::uint32_t>(cycles));
}

// Producers first (DVS, APS, IMU, external input), then the multiplexer, timestamp
// generator, USB FIFO, and last a bias generator that runs only while streaming.
void InivationDevice::stop_modules() {
  config_set(module::dvs, dvs::run, 0);
  if (model_.has_aps) config_set(module::aps, aps::run, 0);
  config_set(module::imu, imu::run_accelerometer, 0);
  config_set(module::imu, imu::run_gyroscope, 0);
  config_set(module::imu, imu::run_temperature, 0);
  config_set(module::extinput, extinput::run_detector, 0);
  config_set(module::mux, mux::run, 0);
  config_set(module::mux, mux::timestamp_run, 0);
  config_set(module::usb, usbmod::run, 0);
  if (model_.chip_runs_while_streaming) config_set(module::mux, mux::run_chip, 0);
}

void InivationDevice::start(EventSink sink) {
  require_open("start()");
  if (streaming_) throw UsbError("start() while already streaming");
  // Leave any earlier, unclean session behind: everything off, let FPGA buffers drain,
  // reset the data endpoint.
  stop_modules();
  wait(std::chrono::milliseconds(10));
  transport_.clear_halt(kDataEndpoint);
  error_.clear();
  transport_.start_bulk_in(
      kDataEndpoint, kTransferSize, kTransferCount,
      [this, sink = std::move(sink)](std::span<const std::uint8_t> bytes) {
        batch_.clear();
        decode(bytes, batch_);
        if (!batch_.empty() && sink) sink(batch_);
      },
      [this](StreamState, const std::string& why) { error_ = why; });  // unplugged or failed
  streaming_ = true;
  if (model_.chip_runs_while_streaming) {
    config_set(module::mux, mux::run_chip, 1);
    wait(std::chrono::milliseconds(200));  // biases settle
  }
  config_set(module::usb, usbmod::run, 1);
  config_set(module::mux, mux::timestamp_run, 1);
  config_set(module::mux, mux::run, 1);
  wait(std::chrono::milliseconds(50));  // data path ready
  config_set(module::dvs, dvs::run, 1);
  start_sensor();
}

void InivationDevice::stop() noexcept {
  if (!streaming_) return;
  streaming_ = false;
  if (transport_.state() != StreamState::disconnected) {  // an unplugged device gets no requests
    try {
      stop_sensor();
      stop_modules();
    } catch (const std::exception& e) {
      if (error_.empty()) error_ = std::string("stopping the device: ") + e.what();
    }
  }
  transport_.stop_bulk_in();
}

void InivationDevice::close() noexcept {
  stop();
  if (!chip_powered_ || transport_.state() == StreamState::disconnected) return;
  chip_powered_ = false;
  try {
    config_set(module::mux, mux::run_chip, 0);  // sensor back in reset
  } catch (const std::exception&) {
    // The device went away while closing: nothing left to put in reset.
  }
}

}  // namespace yelan::camera::usb
