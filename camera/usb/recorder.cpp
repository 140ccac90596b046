#include "camera/usb/recorder.h"

namespace yelan::camera::usb {

RecordResult record(CameraDevice& device, Transport& transport, EventWriter& writer,
                    const std::function<bool()>& keep_going) {
  RecordResult result;
  device.start([&](std::span<const Event> batch) {
    if (result.events == 0) result.t_first = batch.front().t;
    result.t_last = batch.back().t;
    result.events += batch.size();
    writer.write(batch);
  });
  try {
    while (keep_going()) {
      transport.poll(std::chrono::milliseconds(100));
      const StreamState s = transport.state();
      if (s == StreamState::disconnected || s == StreamState::failed) break;
    }
  } catch (...) {
    device.stop();
    throw;
  }
  device.stop();
  result.error = device.error();
  result.stats = device.stats();
  writer.close();
  return result;
}

}  // namespace yelan::camera::usb
