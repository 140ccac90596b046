// The acquisition loop behind `yelan record`: poll the transport, hand each decoded batch
// to an EventWriter, stop when told to (deadline, Ctrl-C) or when the stream ends (unplug),
// and always finish the file so that what was decoded is kept.
#pragma once
#include <functional>
#include <string>

#include "camera/io/event_writer.h"
#include "camera/usb/camera_device.h"

namespace yelan::camera::usb {

struct RecordResult {
  std::uint64_t events = 0;
  std::int64_t t_first = 0, t_last = 0;  // microseconds; meaningful when events > 0
  std::string error;                     // why the stream ended early (unplug), else empty
  DecoderStats stats;
};

// `device` (DavisDevice or DvxplorerDevice) must be open and configured. `keep_going` is
// asked between polls; the loop also ends when the transport reports a disconnect or a
// failure. The writer is closed (renamed into place) in every case; exceptions from the
// writer propagate after stopping the device.
RecordResult record(CameraDevice& device, Transport& transport, EventWriter& writer,
                    const std::function<bool()>& keep_going);

}  // namespace yelan::camera::usb
