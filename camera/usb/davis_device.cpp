#include "camera/usb/davis_device.h"

#include <cmath>
#include <thread>

#include "camera/usb/protocol.h"

namespace yelan::camera::usb {
namespace {

// Data stream transfers: libcaer's defaults for FX3 boards.
constexpr int kTransferCount = 8;
constexpr std::size_t kTransferSize = 8192;

// The DAVIS346 default biases (iniVation's published defaults), in the order sent.
struct BiasWord {
  std::uint8_t address;
  std::uint32_t value;
};
std::vector<BiasWord> davis346_biases() {
  using namespace bias346;
  auto n = [](unsigned c, unsigned f) { return coarse_fine_bias({c, f}); };
  auto p = [](unsigned c, unsigned f) { return coarse_fine_bias({c, f, true, false}); };
  auto n_off = [](unsigned c, unsigned f) { return coarse_fine_bias({c, f, false}); };
  return {
      {aps_overflow_level, vdac_bias(27, 6)}, {aps_cas, vdac_bias(21, 6)},
      {adc_ref_high, vdac_bias(32, 7)},       {adc_ref_low, vdac_bias(1, 7)},
      {adc_test_voltage, vdac_bias(21, 7)},   {local_buf_bn, n(5, 164)},
      {pad_foll_bn, n_off(7, 215)},           {diff_bn, n(4, 39)},
      {on_bn, n(5, 255)},                     {off_bn, n(4, 1)},
      {pix_inv_bn, n(5, 129)},                {pr_bp, p(2, 58)},
      {pr_sf_bp, p(1, 16)},                   {refr_bp, p(4, 25)},
      {readout_buf_bp, p(6, 20)},             {aps_ro_sf_bn, n(6, 219)},
      {adc_comp_bp, p(5, 20)},                {col_sel_low_bn, n(0, 1)},
      {dac_buf_bp, p(6, 60)},                 {lcol_timeout_bn, n(5, 49)},
      {aep_d_bn, n(6, 91)},                   {aep_pu_x_bp, p(4, 80)},
      {aep_pu_y_bp, p(7, 152)},               {if_refr_bn, n(5, 255)},
      {if_thr_bn, n(5, 255)},                 {bias_buffer, n(5, 254)},
      {ssp, shifted_source_bias(1, 33)},      {ssn, shifted_source_bias(1, 33)},
  };
}

// Chip shift-register defaults: muxes to 0, calibration neuron and test pixel held in
// reset, on-chip gray counter for the ADC, ADC reads pixels (not the test voltage).
std::vector<BiasWord> davis346_chip_register() {
  using namespace chip346;
  return {{digital_mux0, 0},       {digital_mux1, 0},        {digital_mux2, 0},
          {digital_mux3, 0},       {analog_mux0, 0},         {analog_mux1, 0},
          {analog_mux2, 0},        {bias_mux0, 0},           {reset_calib_neuron, 1},
          {type_n_calib_neuron, 0}, {reset_test_pixel, 1},   {aer_n_arow, 0},
          {use_aout, 0},           {select_gray_counter, 1}, {test_adc, 0}};
}

}  // namespace

DavisDevice::DavisDevice(Transport& transport, Sleep sleep)
    : transport_(transport), sleep_(std::move(sleep)) {
  if (!sleep_) sleep_ = [](std::chrono::milliseconds d) { std::this_thread::sleep_for(d); };
}

DavisDevice::~DavisDevice() { stop(); }

void DavisDevice::config_set(std::uint8_t module, std::uint8_t param, std::uint32_t value) {
  config_write(transport_, module, param, value);
}

std::uint32_t DavisDevice::config_get(std::uint8_t module, std::uint8_t param) {
  return config_read(transport_, module, param);
}

const DavisInfo& DavisDevice::open() {
  DavisInfo info;
  info.logic_version = config_get(module::sysinfo, sysinfo::logic_version);
  info.chip_id = config_get(module::sysinfo, sysinfo::chip_identifier);
  if (!is_davis346_chip(info.chip_id))
    throw UsbError("unsupported DAVIS chip identifier " + std::to_string(info.chip_id) +
                   " (this driver knows the DAVIS346: 4, 5, 9)");
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
  decoder_ = DavisDecoder(static_cast<std::uint16_t>(columns), static_cast<std::uint16_t>(rows), info.invert_xy);
  return info_;
}

void DavisDevice::configure(const DavisConfig& config) {
  if (info_.width == 0) throw UsbError("configure() before open()");
  config_ = config;
  for (const BiasWord& b : davis346_biases()) config_set(module::chip, b.address, b.value);
  for (const BiasWord& b : davis346_chip_register()) config_set(module::chip, b.address, b.value);
  // Multiplexer: when USB stalls, drop DVS and external-input events rather than
  // back-pressuring the sensor.
  config_set(module::mux, mux::drop_extinput_on_stall, 1);
  config_set(module::mux, mux::drop_dvs_on_stall, 1);
  config_set(module::dvs, dvs::wait_on_stall, 0);
  config_set(module::dvs, dvs::external_aer_control, 0);
  // The early-packet delay is given to the FPGA in USB clock cycles.
  const double cycles = std::round(config.early_packet_delay_us * info_.usb_clock_mhz);
  config_set(module::usb, usbmod::early_packet_delay, static_cast<std::uint32_t>(cycles));
}

// Producers first when stopping (DVS, APS, IMU, external input), then the multiplexer,
// timestamp generator, USB FIFO, and last the chip's bias generator.
void DavisDevice::stop_modules() {
  config_set(module::dvs, dvs::run, 0);
  config_set(module::aps, aps::run, 0);
  config_set(module::imu, imu::run_accelerometer, 0);
  config_set(module::imu, imu::run_gyroscope, 0);
  config_set(module::imu, imu::run_temperature, 0);
  config_set(module::extinput, extinput::run_detector, 0);
  config_set(module::mux, mux::run, 0);
  config_set(module::mux, mux::timestamp_run, 0);
  config_set(module::usb, usbmod::run, 0);
  config_set(module::mux, mux::run_chip, 0);
}

void DavisDevice::start(EventSink sink) {
  if (info_.width == 0) throw UsbError("start() before open()");
  if (streaming_) throw UsbError("start() while already streaming");
  // Leave any earlier, unclean session behind: everything off, let FPGA buffers drain,
  // reset the data endpoint.
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
  config_set(module::mux, mux::run_chip, 1);
  sleep_(std::chrono::milliseconds(200));  // biases settle
  config_set(module::usb, usbmod::run, 1);
  config_set(module::mux, mux::timestamp_run, 1);
  config_set(module::mux, mux::run, 1);
  sleep_(std::chrono::milliseconds(50));  // data path ready
  config_set(module::dvs, dvs::run, 1);
  if (config_.aps) config_set(module::aps, aps::run, 1);
  if (config_.imu) {
    config_set(module::imu, imu::run_accelerometer, 1);
    config_set(module::imu, imu::run_gyroscope, 1);
    config_set(module::imu, imu::run_temperature, 1);
  }
}

void DavisDevice::stop() noexcept {
  if (!streaming_) return;
  streaming_ = false;
  if (transport_.state() != StreamState::disconnected) {
    try {
      stop_modules();
    } catch (const std::exception& e) {
      if (error_.empty()) error_ = std::string("stopping the device: ") + e.what();
    }
  }
  transport_.stop_bulk_in();
}

}  // namespace yelan::camera::usb
