#include "camera/usb/dvxplorer_device.h"

#include <cmath>
#include <thread>

#include "camera/usb/protocol.h"

namespace yelan::camera::usb {
namespace {

constexpr int kTransferCount = 8;
constexpr std::size_t kTransferSize = 8192;

}  // namespace

DvxplorerDevice::DvxplorerDevice(Transport& transport, Sleep sleep)
    : transport_(transport), sleep_(std::move(sleep)) {
  if (!sleep_) sleep_ = [](std::chrono::milliseconds d) { std::this_thread::sleep_for(d); };
}

DvxplorerDevice::~DvxplorerDevice() {
  stop();
  if (powered_ && transport_.state() != StreamState::disconnected) {
    try {
      config_write(transport_, module::mux, mux::run_chip, 0);  // sensor back in reset
    } catch (const std::exception&) {
      // The device went away while closing: nothing left to put in reset.
    }
  }
}

void DvxplorerDevice::sensor(std::uint16_t reg, std::uint32_t value) {
  config_write(transport_, dvx::sensor_module, reg, value & 0xFF);
}

void DvxplorerDevice::sensor_update(std::uint16_t reg, std::uint32_t clear, std::uint32_t set) {
  const std::uint32_t now = config_read(transport_, dvx::sensor_module, reg);
  sensor(reg, (now & ~clear) | set);
}

// iniVation's "default" point of the five simple bias settings.
void DvxplorerDevice::simple_biases() {
  sensor(dvx::bias_amp, 0x04);
  sensor(dvx::bias_range_loga_logd, 0x14);
  sensor(dvx::bias_range_log_sf_on_rst, 0x06);
  sensor(dvx::bias_level_sf_off, 0x7D);
  sensor(dvx::bias_on, 0x00);
  sensor(dvx::bias_off, 0x08);
}

const DvxplorerInfo& DvxplorerDevice::open() {
  DvxplorerInfo info;
  info.logic_version = config_read(transport_, module::sysinfo, sysinfo::logic_version);
  info.chip_id = config_read(transport_, module::sysinfo, sysinfo::chip_identifier);
  if (info.chip_id != dvx::chip_dvxplorer && info.chip_id != dvx::chip_dvxplorer_lite)
    throw UsbError("unsupported DVXplorer chip identifier " + std::to_string(info.chip_id) +
                   " (this driver knows 20: DVXplorer, 19: DVXplorer Lite)");
  const std::uint32_t columns = config_read(transport_, module::dvs, dvs::size_columns);
  const std::uint32_t rows = config_read(transport_, module::dvs, dvs::size_rows);
  if (columns == 0 || rows == 0 || columns > 1024 || rows > 1024)
    throw UsbError("device reports an absurd DVS size " + std::to_string(columns) + "x" + std::to_string(rows));
  info.invert_xy = (config_read(transport_, module::dvs, dvs::orientation) & 0x04) != 0;
  info.width = static_cast<std::uint16_t>(info.invert_xy ? rows : columns);
  info.height = static_cast<std::uint16_t>(info.invert_xy ? columns : rows);
  const double usb_clock = config_read(transport_, module::sysinfo, sysinfo::usb_clock);
  const double deviation = config_read(transport_, module::sysinfo, sysinfo::clock_deviation);
  info.usb_clock_mhz = usb_clock * deviation / 1000.0;
  info_ = info;
  decoder_ = DvxplorerDecoder(static_cast<std::uint16_t>(columns), static_cast<std::uint16_t>(rows), info.invert_xy);

  // Sensor bring-up: out of reset, let it start, then bias generator and output format.
  config_write(transport_, module::mux, mux::run_chip, 1);
  powered_ = true;
  sleep_(std::chrono::milliseconds(10));
  sensor(dvx::bias_otp_trim, 0x24);  // bias reset
  sensor(dvx::bias_pins_dbgp, 0x07);  // bias enable
  sensor(dvx::bias_pins_dbgn, 0xFF);
  sensor(dvx::bias_pins_bufp, 0x03);
  sensor(dvx::bias_pins_bufn, 0x7F);
  sensor(dvx::bias_pins_dob, 0x00);
  simple_biases();
  sensor(dvx::clock_divider_sys, 0xA0);  // system clock divided by 10
  sensor(dvx::parallel_out_control, 0x00);
  sensor(dvx::parallel_out_enable, 0x01);
  sensor(dvx::packet_format, 0x80);  // MGROUP compression: the 8-pixel group words
  sensor(dvx::timestamp_subunit, 0x31);
  sensor(dvx::mode_control, 0x0C);  // R/AY signals enabled
  sensor(dvx::boot_sequence, 0x08);
  sensor(dvx::timing_gh_count_fine, 50);
  sensor(dvx::timing_grs_count_fine, 50);
  sensor(dvx::timing_grs_end_fine, 50);
  sensor(dvx::spatial_histogram_off, 0x01);
  return info_;
}

void DvxplorerDevice::configure() {
  if (info_.width == 0) throw UsbError("configure() before open()");
  const bool lite = info_.chip_id == dvx::chip_dvxplorer_lite;
  // FPGA: drop external-input events when USB is behind; keep DVS events (stall instead).
  config_write(transport_, module::mux, mux::drop_extinput_on_stall, 1);
  config_write(transport_, module::mux, mux::drop_dvs_on_stall, 0);
  config_write(transport_, module::usb, usbmod::early_packet_delay,
               static_cast<std::uint32_t>(std::round(1000.0 * info_.usb_clock_mhz)));  // 1 ms
  simple_biases();
  sensor(dvx::external_trigger, 0);                  // external trigger resets timestamps
  sensor_update(dvx::mode_control, 0x01, 0x01);      // global hold on
  sensor_update(dvx::mode_control, 0x02, 0x00);      // global reset off
  sensor(dvx::global_reset_readout, 0);
  sensor(dvx::fixed_read_time, 0);
  sensor_update(dvx::packet_format, 0x70, 0x00);     // no polarity flattening or filtering
  sensor_update(dvx::digital_enable, 0x06, 0x06);    // subsampling and area blocking off
  if (!lite) sensor(dvx::dual_binning, 0);
  const std::uint32_t no_subsample = lite ? 1 : 0;   // the Lite counts in half steps
  sensor_update(dvx::subsample_ratio, 0x38, no_subsample << 3);
  sensor_update(dvx::subsample_ratio, 0x07, no_subsample);
  for (std::uint16_t i = 0; i < 20; ++i) {  // area blocks all open (0x7FFF)
    sensor(static_cast<std::uint16_t>(dvx::area_block + 2 * i), 0x7F);
    sensor(static_cast<std::uint16_t>(dvx::area_block + 2 * i + 1), 0xFF);
  }
  // Readout timing (sensor clock cycles).
  sensor(dvx::timing_gh_count, 0x00), sensor(dvx::timing_gh_count + 1, 0x00), sensor(dvx::timing_gh_count + 2, 0x02);
  sensor(dvx::timing_grs_count, 0x00), sensor(dvx::timing_grs_count + 1, 0x00), sensor(dvx::timing_grs_count + 2, 0x00);
  sensor(dvx::timing_grs_end, 0x00), sensor(dvx::timing_grs_end + 1, 0x00), sensor(dvx::timing_grs_end + 2, 0x01);
  sensor(dvx::timing_first_selx_start, 4);
  sensor(dvx::timing_selx_width, 6);
  sensor(dvx::timing_ay_start, 4);
  sensor(dvx::timing_ay_end, 6);
  sensor(dvx::timing_r_start, 8);
  sensor(dvx::timing_r_end, 10);
  sensor(dvx::timing_next_selx_start, 0), sensor(dvx::timing_next_selx_start + 1, 15);
  sensor(dvx::timing_max_event_num, 10);  // next-select - 5
  sensor(dvx::timing_next_gh_cnt, 10);
  sensor(dvx::timing_read_time_interval, 48000 >> 8), sensor(dvx::timing_read_time_interval + 1, 48000 & 0xFF);
  // Cropper bypassed, its window the full array.
  sensor(dvx::cropper_bypass, 0x01);
  const unsigned last_row = info_.height - 1u, last_col = info_.width - 1u;
  sensor(dvx::cropper_y_start_group, 0);
  sensor(dvx::cropper_y_start_mask, 0xFF);
  sensor(dvx::cropper_y_end_group, last_row / 8);
  sensor(dvx::cropper_y_end_mask, 0xFFu >> (7 - last_row % 8));
  sensor(dvx::cropper_x_start, 0), sensor(dvx::cropper_x_start + 1, 0);
  sensor(dvx::cropper_x_end, last_col >> 8), sensor(dvx::cropper_x_end + 1, last_col & 0xFF);
  // Activity-decision filter bypassed (thresholds at their defaults).
  sensor(dvx::activity_bypass, 0x01);
  sensor(dvx::activity_pos_threshold, 300 >> 8), sensor(dvx::activity_pos_threshold + 1, 300 & 0xFF);
  sensor(dvx::activity_neg_threshold, 0), sensor(dvx::activity_neg_threshold + 1, 20);
  sensor(dvx::activity_dec_rate, 1);
  sensor(dvx::activity_dec_time, 3);
  sensor(dvx::activity_pos_max_count, 300 >> 8), sensor(dvx::activity_pos_max_count + 1, 300 & 0xFF);
  sensor(dvx::digital_restart, 0x02);  // restart the sensor's digital block with all this
}

void DvxplorerDevice::stop_modules() {
  config_write(transport_, module::dvs, dvs::run, 0);
  config_write(transport_, module::imu, imu::run_accelerometer, 0);
  config_write(transport_, module::imu, imu::run_gyroscope, 0);
  config_write(transport_, module::imu, imu::run_temperature, 0);
  config_write(transport_, module::extinput, extinput::run_detector, 0);
  config_write(transport_, module::mux, mux::run, 0);
  config_write(transport_, module::mux, mux::timestamp_run, 0);
  config_write(transport_, module::usb, usbmod::run, 0);
}

void DvxplorerDevice::start(EventSink sink) {
  if (info_.width == 0) throw UsbError("start() before open()");
  if (streaming_) throw UsbError("start() while already streaming");
  stop_modules();
  sleep_(std::chrono::milliseconds(10));
  transport_.clear_halt(kDataEndpoint);
  error_.clear();
  transport_.start_bulk_in(
      kDataEndpoint, kTransferSize, kTransferCount,
      [this, sink = std::move(sink)](std::span<const std::uint8_t> bytes) {
        batch_.clear();
        decoder_.feed(bytes, batch_);
        if (!batch_.empty() && sink) sink(batch_);
      },
      [this](StreamState, const std::string& why) { error_ = why; });
  streaming_ = true;
  config_write(transport_, module::usb, usbmod::run, 1);
  config_write(transport_, module::mux, mux::timestamp_run, 1);
  config_write(transport_, module::mux, mux::run, 1);
  sleep_(std::chrono::milliseconds(50));
  config_write(transport_, module::dvs, dvs::run, 1);
  sensor(dvx::timestamp_reset, 1);  // sensor timestamp reset pulse
  sensor(dvx::timestamp_reset, 0);
  sensor(dvx::control_mode, dvx::mode_stream);
}

void DvxplorerDevice::stop() noexcept {
  if (!streaming_) return;
  streaming_ = false;
  if (transport_.state() != StreamState::disconnected) {
    try {
      sensor(dvx::control_mode, dvx::mode_off);
      stop_modules();
    } catch (const std::exception& e) {
      if (error_.empty()) error_ = std::string("stopping the device: ") + e.what();
    }
  }
  transport_.stop_bulk_in();
}

}  // namespace yelan::camera::usb
