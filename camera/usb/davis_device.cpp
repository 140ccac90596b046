#include "camera/usb/davis_device.h"

#include "camera/usb/protocol.h"

namespace yelan::camera::usb {
namespace {

constexpr InivationModel kDavis346 = {"DAVIS", is_davis346_chip, "the DAVIS346: 4, 5, 9", /*has_aps=*/true,
                                      /*chip_runs_while_streaming=*/true};

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
    : InivationDevice(transport, std::move(sleep), kDavis346) {}

void DavisDevice::configure(const DavisConfig& config) {
  require_open("configure()");
  config_ = config;
  for (const BiasWord& b : davis346_biases()) config_set(module::chip, b.address, b.value);
  for (const BiasWord& b : davis346_chip_register()) config_set(module::chip, b.address, b.value);
  // Multiplexer: when USB stalls, drop DVS and external-input events rather than
  // back-pressuring the sensor.
  config_set(module::mux, mux::drop_extinput_on_stall, 1);
  config_set(module::mux, mux::drop_dvs_on_stall, 1);
  config_set(module::dvs, dvs::wait_on_stall, 0);
  config_set(module::dvs, dvs::external_aer_control, 0);
  set_early_packet_delay(config.early_packet_delay_us);
}

void DavisDevice::start_sensor() {
  if (config_.aps) config_set(module::aps, aps::run, 1);
  if (config_.imu) {
    config_set(module::imu, imu::run_accelerometer, 1);
    config_set(module::imu, imu::run_gyroscope, 1);
    config_set(module::imu, imu::run_temperature, 1);
  }
}

}  // namespace yelan::camera::usb
