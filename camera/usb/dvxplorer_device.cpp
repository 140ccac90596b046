#include "camera/usb/dvxplorer_device.h"

#include "camera/usb/protocol.h"

namespace yelan::camera::usb {
namespace {

bool is_dvxplorer_chip(std::uint32_t id) { return id == dvx::chip_dvxplorer || id == dvx::chip_dvxplorer_lite; }

constexpr InivationModel kDvxplorer = {"DVXplorer", is_dvxplorer_chip, "20: DVXplorer, 19: DVXplorer Lite",
                                       /*has_aps=*/false, /*chip_runs_while_streaming=*/false};

// One 8-bit sensor register and its value. The tables below are iniVation's values, kept
// literal and in libcaer's order so that they can be checked against it line by line.
struct SensorWrite {
  std::uint16_t reg;
  std::uint8_t value;
};

// Bias generator reset (OTP trim), then its pins enabled.
constexpr SensorWrite kBiasEnable[] = {
    {dvx::bias_otp_trim, 0x24},  {dvx::bias_pins_dbgp, 0x07}, {dvx::bias_pins_dbgn, 0xFF},
    {dvx::bias_pins_bufp, 0x03}, {dvx::bias_pins_bufn, 0x7F}, {dvx::bias_pins_dob, 0x00}};

// iniVation's "default" point of the five simple bias settings.
constexpr SensorWrite kSimpleBiases[] = {
    {dvx::bias_amp, 0x04},          {dvx::bias_range_loga_logd, 0x14}, {dvx::bias_range_log_sf_on_rst, 0x06},
    {dvx::bias_level_sf_off, 0x7D}, {dvx::bias_on, 0x00},              {dvx::bias_off, 0x08}};

// System clock divided by 10, parallel output on, MGROUP compression (the 8-pixel group
// words), timestamp sub-unit, R/AY signals enabled, boot sequence, fine timing counts.
constexpr SensorWrite kOutputFormat[] = {
    {dvx::clock_divider_sys, 0xA0}, {dvx::parallel_out_control, 0x00}, {dvx::parallel_out_enable, 0x01},
    {dvx::packet_format, 0x80},     {dvx::timestamp_subunit, 0x31},    {dvx::mode_control, 0x0C},
    {dvx::boot_sequence, 0x08},     {dvx::timing_gh_count_fine, 50},   {dvx::timing_grs_count_fine, 50},
    {dvx::timing_grs_end_fine, 50}, {dvx::spatial_histogram_off, 0x01}};

// Readout timing in sensor clock cycles; multi-byte values high byte first. The maximum
// event number is the next-select start minus 5.
constexpr SensorWrite kReadoutTiming[] = {
    {dvx::timing_gh_count, 0x00}, {dvx::timing_gh_count + 1, 0x00}, {dvx::timing_gh_count + 2, 0x02},
    {dvx::timing_grs_count, 0x00}, {dvx::timing_grs_count + 1, 0x00}, {dvx::timing_grs_count + 2, 0x00},
    {dvx::timing_grs_end, 0x00}, {dvx::timing_grs_end + 1, 0x00}, {dvx::timing_grs_end + 2, 0x01},
    {dvx::timing_first_selx_start, 4}, {dvx::timing_selx_width, 6}, {dvx::timing_ay_start, 4},
    {dvx::timing_ay_end, 6}, {dvx::timing_r_start, 8}, {dvx::timing_r_end, 10},
    {dvx::timing_next_selx_start, 0}, {dvx::timing_next_selx_start + 1, 15}, {dvx::timing_max_event_num, 10},
    {dvx::timing_next_gh_cnt, 10}, {dvx::timing_read_time_interval, 48000 >> 8},
    {dvx::timing_read_time_interval + 1, 48000 & 0xFF}};

// Activity-decision filter bypassed, its thresholds at their defaults (300 / 20, rate 1,
// time 3, max 300).
constexpr SensorWrite kActivityFilterBypassed[] = {
    {dvx::activity_bypass, 0x01}, {dvx::activity_pos_threshold, 300 >> 8},
    {dvx::activity_pos_threshold + 1, 300 & 0xFF}, {dvx::activity_neg_threshold, 0},
    {dvx::activity_neg_threshold + 1, 20}, {dvx::activity_dec_rate, 1}, {dvx::activity_dec_time, 3},
    {dvx::activity_pos_max_count, 300 >> 8}, {dvx::activity_pos_max_count + 1, 300 & 0xFF}};

void write_sensor(InivationDevice& device, std::span<const SensorWrite> table) {
  for (const SensorWrite& w : table) device.config_set(dvx::sensor_module, w.reg, w.value);
}

}  // namespace

DvxplorerDevice::DvxplorerDevice(Transport& transport, Sleep sleep)
    : InivationDevice(transport, std::move(sleep), kDvxplorer) {}

void DvxplorerDevice::sensor(std::uint16_t reg, std::uint32_t value) {
  config_set(dvx::sensor_module, reg, value & 0xFF);
}

void DvxplorerDevice::sensor_update(std::uint16_t reg, std::uint32_t clear, std::uint32_t set) {
  const std::uint32_t now = config_get(dvx::sensor_module, reg);
  sensor(reg, (now & ~clear) | set);
}

// Out of reset, let the sensor start, then bias generator and output format.
void DvxplorerDevice::bring_up() {
  power_chip();
  wait(std::chrono::milliseconds(10));
  write_sensor(*this, kBiasEnable);
  write_sensor(*this, kSimpleBiases);
  write_sensor(*this, kOutputFormat);
}

void DvxplorerDevice::configure() {
  require_open("configure()");
  const bool lite = info().chip_id == dvx::chip_dvxplorer_lite;
  // FPGA: drop external-input events when USB is behind; keep DVS events (stall instead).
  config_set(module::mux, mux::drop_extinput_on_stall, 1);
  config_set(module::mux, mux::drop_dvs_on_stall, 0);
  set_early_packet_delay(1000);
  write_sensor(*this, kSimpleBiases);
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
  write_sensor(*this, kReadoutTiming);
  // Cropper bypassed, its window the full array.
  sensor(dvx::cropper_bypass, 0x01);
  const unsigned last_row = info().height - 1u, last_col = info().width - 1u;
  sensor(dvx::cropper_y_start_group, 0);
  sensor(dvx::cropper_y_start_mask, 0xFF);
  sensor(dvx::cropper_y_end_group, last_row / 8);
  sensor(dvx::cropper_y_end_mask, 0xFFu >> (7 - last_row % 8));
  sensor(dvx::cropper_x_start, 0), sensor(dvx::cropper_x_start + 1, 0);
  sensor(dvx::cropper_x_end, last_col >> 8), sensor(dvx::cropper_x_end + 1, last_col & 0xFF);
  write_sensor(*this, kActivityFilterBypassed);
  sensor(dvx::digital_restart, 0x02);  // restart the sensor's digital block with all this
}

void DvxplorerDevice::start_sensor() {
  sensor(dvx::timestamp_reset, 1);  // sensor timestamp reset pulse
  sensor(dvx::timestamp_reset, 0);
  sensor(dvx::control_mode, dvx::mode_stream);
}

void DvxplorerDevice::stop_sensor() { sensor(dvx::control_mode, dvx::mode_off); }

}  // namespace yelan::camera::usb
