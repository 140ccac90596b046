#include "camera/usb/camera_device.h"

#include "camera/usb/protocol.h"

namespace yelan::camera::usb {

void config_write(Transport& t, std::uint8_t module, std::uint16_t param, std::uint32_t value) {
  const std::uint8_t be[4] = {std::uint8_t(value >> 24), std::uint8_t(value >> 16), std::uint8_t(value >> 8),
                              std::uint8_t(value)};
  t.control_out(kRequestConfig, module, param, be);
}

std::uint32_t config_read(Transport& t, std::uint8_t module, std::uint16_t param) {
  const std::vector<std::uint8_t> be = t.control_in(kRequestConfig, module, param, 4);
  if (be.size() != 4)
    throw UsbError("config read of module " + std::to_string(module) + " parameter " + std::to_string(param) +
                   " returned " + std::to_string(be.size()) + " bytes, expected 4");
  return (std::uint32_t(be[0]) << 24) | (std::uint32_t(be[1]) << 16) | (std::uint32_t(be[2]) << 8) | be[3];
}

}  // namespace yelan::camera::usb
