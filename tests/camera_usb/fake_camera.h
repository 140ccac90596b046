// A scripted DAVIS346 (346 x 260) over the fake transport, and whether the user says a real
// camera is attached (YELAN_CAMERA_ATTACHED=1), for the camera_usb CLI tests.
#pragma once
#include <cstdlib>
#include <string>

#include "camera/usb/fake_transport.h"
#include "camera/usb/protocol.h"

namespace yelan::test::usb {

inline camera::usb::FakeTransport fake_davis346() {
  namespace p = camera::usb;
  p::FakeTransport t;
  t.set_config(p::module::sysinfo, p::sysinfo::chip_identifier, 4);
  t.set_config(p::module::dvs, p::dvs::size_columns, 346);
  t.set_config(p::module::dvs, p::dvs::size_rows, 260);
  return t;
}

// No camera is attached to the machines that run this suite unless the user says so.
inline bool camera_attached() {
  const char* v = std::getenv("YELAN_CAMERA_ATTACHED");
  return v && *v && std::string(v) != "0";
}

}  // namespace yelan::test::usb
