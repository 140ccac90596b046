// The iniVation USB protocol as this driver uses it: identifiers, the vendor request that
// carries configuration, module/parameter addresses, and how bias words are packed.
// Learnt from the public libcaer sources; camera/usb/README.md states it in prose and tables.
#pragma once
#include <cstdint>

namespace yelan::camera::usb {

inline constexpr std::uint16_t kVendorId = 0x152A;
inline constexpr std::uint16_t kDavis346ProductId = 0x841A;  // FX3-based DAVIS boards
inline constexpr std::uint16_t kDvxplorerProductId = 0x8419;
inline constexpr std::uint8_t kDataEndpoint = 0x82;  // bulk IN, 16-bit event words
inline constexpr int kConfiguration = 1;
inline constexpr int kInterface = 0;

// Vendor control request carrying one 32-bit configuration value, big-endian, 4 bytes:
// OUT (bmRequestType 0x40) writes, IN (0xC0) reads; wValue = module, wIndex = parameter.
inline constexpr std::uint8_t kRequestConfig = 0xBF;
inline constexpr std::uint8_t kRequestTypeOut = 0x40;
inline constexpr std::uint8_t kRequestTypeIn = 0xC0;

// Module addresses (wValue) of the DAVIS FPGA logic.
namespace module {
inline constexpr std::uint8_t mux = 0, dvs = 1, aps = 2, imu = 3, extinput = 4, chip = 5,
                              sysinfo = 6, usb = 9;
}

// Parameter addresses (wIndex) within each module, only those this driver touches.
namespace mux {
inline constexpr std::uint8_t run = 0, timestamp_run = 1, timestamp_reset = 2, run_chip = 3,
                              drop_extinput_on_stall = 4, drop_dvs_on_stall = 5;
}
namespace dvs {
inline constexpr std::uint8_t size_columns = 0, size_rows = 1, orientation = 2, run = 3,
                              wait_on_stall = 4, external_aer_control = 5;
}
namespace aps {
inline constexpr std::uint8_t run = 4;
}
namespace imu {
inline constexpr std::uint8_t run_accelerometer = 2, run_gyroscope = 3, run_temperature = 4;
}
namespace extinput {
inline constexpr std::uint8_t run_detector = 0;
}
namespace sysinfo {
inline constexpr std::uint8_t logic_version = 0, chip_identifier = 1, device_is_master = 2,
                              logic_clock = 3, adc_clock = 4, usb_clock = 5, clock_deviation = 6;
}
namespace usbmod {
inline constexpr std::uint8_t run = 0, early_packet_delay = 1;
}

// DAVIS346 bias generator (module 5, parameters 0..36) and chip shift register (128..144).
namespace bias346 {
inline constexpr std::uint8_t aps_overflow_level = 0, aps_cas = 1, adc_ref_high = 2,
                              adc_ref_low = 3, adc_test_voltage = 4, local_buf_bn = 8,
                              pad_foll_bn = 9, diff_bn = 10, on_bn = 11, off_bn = 12,
                              pix_inv_bn = 13, pr_bp = 14, pr_sf_bp = 15, refr_bp = 16,
                              readout_buf_bp = 17, aps_ro_sf_bn = 18, adc_comp_bp = 19,
                              col_sel_low_bn = 20, dac_buf_bp = 21, lcol_timeout_bn = 22,
                              aep_d_bn = 23, aep_pu_x_bp = 24, aep_pu_y_bp = 25,
                              if_refr_bn = 26, if_thr_bn = 27, bias_buffer = 34, ssp = 35,
                              ssn = 36;
}
namespace chip346 {
inline constexpr std::uint8_t digital_mux0 = 128, digital_mux1 = 129, digital_mux2 = 130,
                              digital_mux3 = 131, analog_mux0 = 132, analog_mux1 = 133,
                              analog_mux2 = 134, bias_mux0 = 135, reset_calib_neuron = 136,
                              type_n_calib_neuron = 137, reset_test_pixel = 138,
                              aer_n_arow = 140, use_aout = 141, global_shutter = 142,
                              select_gray_counter = 143, test_adc = 144;
}

// Chip identifiers reported by SYSINFO/chip_identifier that are 346x260 sensors.
inline constexpr bool is_davis346_chip(std::uint32_t id) { return id == 4 || id == 5 || id == 9; }

// Bias words. A voltage DAC bias: voltage 0..63 (fraction of VDD/64) in bits 5:0, current
// 0..7 in bits 8:6.
constexpr std::uint32_t vdac_bias(unsigned voltage, unsigned current) {
  return (voltage & 0x3Fu) | ((current & 0x07u) << 6);
}
// A coarse-fine current bias: bit0 enabled, bit1 N-type (else P), bit2 normal (else
// cascode), bit3 normal current level (else low), fine 0..255 in bits 11:4, coarse 0..7 in
// bits 14:12.
struct CoarseFine {
  unsigned coarse, fine;
  bool enabled = true, n_type = true, normal = true, normal_level = true;
};
constexpr std::uint32_t coarse_fine_bias(const CoarseFine& b) {
  return (b.enabled ? 1u : 0u) | (b.n_type ? 2u : 0u) | (b.normal ? 4u : 0u) |
         (b.normal_level ? 8u : 0u) | ((b.fine & 0xFFu) << 4) | ((b.coarse & 0x07u) << 12);
}
// A shifted-source bias: bits 1:0 mode (0 shifted source, 1 high impedance, 2 tied to rail),
// bits 3:2 voltage level (0 split gate, 1 single diode, 2 double diode), ref 0..63 in bits
// 9:4, reg 0..63 in bits 15:10.
constexpr std::uint32_t shifted_source_bias(unsigned ref, unsigned reg, unsigned mode = 0,
                                            unsigned level = 0) {
  return (mode & 0x3u) | ((level & 0x3u) << 2) | ((ref & 0x3Fu) << 4) | ((reg & 0x3Fu) << 10);
}

}  // namespace yelan::camera::usb

namespace yelan::camera::usb {

// DVXplorer: the FPGA modules MUX, DVS, IMU, external input, SYSINFO and USB sit at the
// same addresses with the same parameters as on DAVIS. The Samsung sensor's own 8-bit
// registers are reached through module 5 with the 16-bit register address as parameter.
namespace dvx {
inline constexpr std::uint8_t sensor_module = 5;
inline constexpr std::uint32_t chip_dvxplorer = 20, chip_dvxplorer_lite = 19;  // 640x480, 320x240
// Sensor register addresses.
inline constexpr std::uint16_t bias_range_log_sf_on_rst = 0x000B, bias_range_loga_logd = 0x000C,
                               bias_otp_trim = 0x000D, bias_pins_dbgp = 0x000F, bias_pins_dbgn = 0x0010,
                               bias_level_sf_off = 0x0012, bias_pins_bufp = 0x0013,
                               bias_pins_bufn = 0x0014, bias_pins_dob = 0x0015, bias_amp = 0x0018,
                               bias_on = 0x001C, bias_off = 0x001E;
inline constexpr std::uint16_t control_mode = 0x3000, clock_divider_sys = 0x3011,
                               parallel_out_control = 0x3019, parallel_out_enable = 0x301E,
                               packet_format = 0x3067;
inline constexpr std::uint16_t digital_enable = 0x3200, digital_restart = 0x3201,
                               dual_binning = 0x3202, subsample_ratio = 0x3204, area_block = 0x3205,
                               timestamp_subunit = 0x3234, timestamp_reset = 0x3238,
                               timing_first_selx_start = 0x323C, timing_gh_count = 0x3240,
                               timing_gh_count_fine = 0x3243, timing_grs_count = 0x3244,
                               timing_grs_count_fine = 0x3247, global_reset_readout = 0x3248,
                               timing_next_gh_cnt = 0x324B, timing_selx_width = 0x324C,
                               timing_ay_start = 0x324E, timing_ay_end = 0x324F,
                               timing_max_event_num = 0x3251, timing_r_start = 0x3253,
                               timing_r_end = 0x3254, mode_control = 0x3255, timing_grs_end = 0x3256,
                               timing_grs_end_fine = 0x3259, fixed_read_time = 0x325C,
                               timing_read_time_interval = 0x325D, external_trigger = 0x3260,
                               timing_next_selx_start = 0x3261, boot_sequence = 0x3266;
inline constexpr std::uint16_t cropper_bypass = 0x3300, cropper_y_start_group = 0x3301,
                               cropper_y_start_mask = 0x3302, cropper_y_end_group = 0x3303,
                               cropper_y_end_mask = 0x3304, cropper_x_start = 0x3305,
                               cropper_x_end = 0x3307;
inline constexpr std::uint16_t activity_bypass = 0x3500, activity_pos_threshold = 0x3501,
                               activity_neg_threshold = 0x3503, activity_dec_rate = 0x3505,
                               activity_dec_time = 0x3506, activity_pos_max_count = 0x3513;
inline constexpr std::uint16_t spatial_histogram_off = 0x3600;
// control_mode values.
inline constexpr std::uint32_t mode_off = 0, mode_stream = 2;
}  // namespace dvx

}  // namespace yelan::camera::usb
